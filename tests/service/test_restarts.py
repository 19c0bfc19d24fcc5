"""Finding C1 of issue 33: a graceful stop (SIGTERM) is not the job's fault. Jobs a stopping
server leaves queued or running are re-queued without counting a start against them; only
a job the store shows *running* when a server died (SIGKILL, a crash) counts one."""
from __future__ import annotations

import time

from bsdflab.jobs import register_kind
from bsdflab.service.auth import ANONYMOUS
from bsdflab.service.job_service import MAX_ATTEMPTS, JobService
from bsdflab.service.settings import Settings

register_kind("test-steps", "support.job_kinds")
SLOW = {"steps": 400, "step_s": 0.05}   # 20 s: still running when the service stops


def _service(tmp_path) -> JobService:
    return JobService(Settings(data_dir=tmp_path, cache_dir=tmp_path / "tables",
                               executor="threads", workers=1, progress_interval_s=0.02))


def _wait_running(service: JobService, job_id: str, timeout: float = 60.0) -> None:
    end = time.monotonic() + timeout
    while service.store.job(job_id)["state"] != "running":
        assert time.monotonic() < end, service.store.job(job_id)
        time.sleep(0.02)


def test_graceful_restarts_never_fail_a_running_or_a_queued_job(tmp_path):
    """Before: both jobs failed "gave up after 3 starts" after three stops a few seconds
    apart, the queued one without ever running. Mutation caught: counting a start on a
    graceful stop (``close`` without ``store.release_running()``) fails the running job."""
    service = _service(tmp_path)
    running, _ = service.submit("test-steps", {**SLOW, "n": 1}, "a" * 64, ANONYMOUS)
    queued, _ = service.submit("test-steps", {**SLOW, "n": 2}, "b" * 64, ANONYMOUS)
    _wait_running(service, running["id"])
    for _ in range(MAX_ATTEMPTS + 2):
        service.close()
        service = _service(tmp_path)
        _wait_running(service, running["id"])
    states = {r["id"]: (r["state"], r["attempts"]) for r in (service.store.job(running["id"]),
                                                            service.store.job(queued["id"]))}
    service.close()
    assert states == {running["id"]: ("running", 0), queued["id"]: ("queued", 0)}


def test_a_job_running_when_its_server_died_counts_a_start(tmp_path):
    """The crash guard stays: a job the store shows running at start (the last server was
    killed while it ran) counts a start, and the third such start fails it. Mutation caught:
    never counting (the guard gone) leaves the job queued."""
    service = _service(tmp_path)
    row, _ = service.submit("test-steps", {**SLOW, "n": 3}, "c" * 64, ANONYMOUS)
    _wait_running(service, row["id"])
    service._stop.set()            # a SIGKILL: no graceful close runs, the store still says running
    service._monitor.join()
    service.executor.shutdown()
    for attempt in range(1, MAX_ATTEMPTS + 1):
        service = _service(tmp_path)
        if attempt < MAX_ATTEMPTS:
            assert service.store.job(row["id"])["attempts"] == attempt
            _wait_running(service, row["id"])
            service._stop.set()
            service._monitor.join()
            service.executor.shutdown()
    found = service.store.job(row["id"])
    service.close()
    assert found["state"] == "failed" and found["error_type"] == "Interrupted"


def test_a_job_cancelled_before_a_graceful_stop_is_not_run_again(tmp_path):
    """A cancel is noticed at the job's next stopping point (a validation check, a
    benchmark: minutes); a graceful stop before it re-queued the job, and every start ran
    it again. Here the job sleeps 3 s between its points and the service stops at once
    after the cancel. Mutation caught: ``close`` without recording the asked cancels (the
    job is queued and starts again)."""
    service = _service(tmp_path)
    row, _ = service.submit("test-steps", {"steps": 2, "step_s": 3.0, "n": 4}, "d" * 64, ANONYMOUS)
    _wait_running(service, row["id"])
    assert service.cancel(row["id"])
    service.close()
    service = _service(tmp_path)
    found = service.store.job(row["id"])
    service.close()
    assert found["state"] == "cancelled", found
