"""Review of the check workers (merge 2ed4d37): one failed worker start must not stop the
pool for good. ``ProcessJobExecutor._loop`` lets an exception of ``_spawn`` (fork/spawn's
OSError: EMFILE under many connections, EAGAIN, ENOMEM) end the dispatcher thread without
setting ``_stopping``: ``submit`` still queues, nothing ever runs, and every upload / render
check of the service waits out BSDFLAB_CHECK_DEADLINE_S and is a 503 until the server is
restarted. Fails at 2ed4d37 (TimeoutError). Fix: catch the spawn's error in the loop (fail
the waiting job, or retry with a back-off), or mark the executor stopped so submit raises."""
from __future__ import annotations

from bsdflab.jobs import processes, register_kind
from bsdflab.jobs.processes import ProcessJobExecutor
from support.liveness import HANG_S, wait_until

register_kind("test-steps", "support.job_kinds")


def test_a_failed_worker_start_does_not_stop_the_pool_for_good(tmp_path, monkeypatch):
    real, calls = processes._Worker, []

    def flaky(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:   # the replacement of a worker that died: the fork fails once
            raise OSError(24, "Too many open files")
        return real(*args, **kwargs)

    monkeypatch.setattr(processes, "_Worker", flaky)
    executor = ProcessJobExecutor(1, cancel_grace_s=0.0, warm=False)
    try:
        assert executor.submit("test-steps", {"steps": 1, "step_s": 0.0}, tmp_path).result(HANG_S)
        pid = executor.worker_pids()[0]
        import os
        import signal
        os.kill(pid, signal.SIGKILL)   # a check past its deadline is killed the same way
        wait_until(lambda: not executor.worker_pids(), "retired worker")
        first = executor.submit("test-steps", {"steps": 1, "step_s": 0.0}, tmp_path)
        try:   # the job that met the failed start may fail (or wait for a retried start)
            first.result(20)
        except Exception:   # noqa: BLE001
            pass
        later = executor.submit("test-steps", {"steps": 1, "step_s": 0.0}, tmp_path)
        assert later.result(HANG_S)   # at 2ed4d37: TimeoutError, the dispatcher thread is gone
    finally:
        executor.shutdown()
