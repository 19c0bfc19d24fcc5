"""Stopping the process executor (a server's stop) never waits on a worker that is still
starting. Such a worker reads no message until its imports end (seconds under load), so the
"stop" sent to it was only seen after them, and every server stop waited up to 5 s per pool.
It has no job: the executor kills it at once. Checked by the order of the calls on the
worker's process (a kill before any join), not by a clock."""
from __future__ import annotations

import signal

from bsdflab.jobs import processes, register_kind
from bsdflab.jobs.processes import ProcessJobExecutor
from support import job_kinds

register_kind("test-steps", "support.job_kinds")


def test_a_worker_still_starting_is_killed_at_shutdown_not_waited_for(monkeypatch):
    """Mutation: sending it "stop" and joining first (the old `_stop_all`) records a join on
    a live, unkilled process and fails the order check."""
    calls: list[tuple[str, bool]] = []
    real = processes._Worker

    class Recorded(real):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            process, join, kill = self.process, self.process.join, self.process.kill
            killed = []

            def recorded_kill():
                killed.append(True)
                calls.append(("kill", True))
                kill()

            def recorded_join(timeout=None):
                calls.append(("join", bool(killed) or process.exitcode is not None))
                join(timeout)

            process.kill, process.join = recorded_kill, recorded_join

    monkeypatch.setattr(processes, "worker_main", job_kinds.never_ready)   # pickled by name: the child runs it
    monkeypatch.setattr(processes, "_Worker", Recorded)
    executor = ProcessJobExecutor(1, warm=False)
    executor.shutdown()   # the dispatcher's first act is to start a worker, so there is one
    joins = [ok for name, ok in calls if name == "join"]
    assert calls and calls[0] == ("kill", True), calls
    assert joins and all(joins), calls
    assert executor.worker_pids() == []


def test_an_idle_ready_worker_is_told_to_stop_and_exits_cleanly(tmp_path):
    """The other branch: a ready worker without a job exits on "stop" (code 0), not by a kill.
    Mutation: killing every worker gives exit code -9."""
    executor = ProcessJobExecutor(1, warm=False)
    try:
        assert executor.submit("test-steps", {"steps": 1, "step_s": 0.0}, tmp_path).result(120)
        with executor._lock:
            (worker,) = executor._pool
    finally:
        executor.shutdown()
    assert worker.process.exitcode == 0, worker.process.exitcode
    assert worker.process.exitcode != -signal.SIGKILL
