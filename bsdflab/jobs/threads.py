"""Jobs on threads of this process (the C++ core releases the GIL while it works), and the
same with the jobs' work units on a runner (bsdflab.util.runners)."""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from bsdflab.jobs.executor import JobExecutor, JobHandle, execute, outcome_error
from bsdflab.util.progress import JobCancelled
from bsdflab.util.runners import Runner, open_runner


class ThreadJobExecutor(JobExecutor):
    """``workers`` jobs at a time on a thread pool; a cancelled queued job never starts,
    a running one stops at its next progress check (within about 0.2 s). ``runner``: the
    runner the jobs hand their work units to (None: the API's in-process path)."""

    def __init__(self, workers: int = 1, runner: Runner | None = None):
        self.workers = workers
        self.runner = runner
        self._pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="bsdflab-job")
        self._handles: set[JobHandle] = set()

    def submit(self, kind: str, request: dict[str, Any], out_dir: str | os.PathLike) -> JobHandle:
        handle = JobHandle(kind, request, out_dir)
        handle._on_cancel = _cancel_if_queued
        self._handles.add(handle)
        self._pool.submit(self._run, handle)
        return handle

    def _run(self, handle: JobHandle) -> None:
        try:
            if not handle._started():
                return
            outcome = execute(handle.kind, handle.request, handle.out_dir, handle._progress,
                              handle.cancel_requested, runner=self.runner)
            handle._finish(outcome[1] if outcome[0] == "done" else None, outcome_error(outcome))
        finally:
            self._handles.discard(handle)

    def shutdown(self) -> None:
        for handle in list(self._handles):
            handle.cancel()
        self._pool.shutdown(wait=True, cancel_futures=True)
        for handle in list(self._handles):   # queued futures the pool dropped
            handle._finish(error=JobCancelled("executor shut down"))


class RunnerJobExecutor(ThreadJobExecutor):
    """``workers`` concurrent job drivers on threads here, sharing one runner connection
    (``spec`` = ``"<runner>:<target>"``, e.g. ``"dask:tcp://HOST:8786"``): the job functions
    are the other executors' own; their work units go to the runner. Progress and cancel
    reach the units through the job monitor (bsdflab.util.progress): the runner reports each
    finished unit and cancels the outstanding ones when the job is cancelled."""

    def __init__(self, spec: str, workers: int = 1):
        self._connection = open_runner(spec)
        runner = self._connection.__enter__()  # ConnectionError before any job is accepted
        super().__init__(workers, runner)

    def shutdown(self) -> None:
        try:
            super().shutdown()
        finally:
            if self._connection is not None:
                self._connection.__exit__(None, None, None)
                self._connection = None


def _cancel_if_queued(handle: JobHandle) -> None:
    handle._finish(error=JobCancelled("cancelled before it started"), if_queued=True)
