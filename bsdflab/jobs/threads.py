"""Jobs on threads of this process (the C++ core releases the GIL while it works)."""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from bsdflab.util.progress import JobCancelled
from bsdflab.jobs.executor import JobExecutor, JobHandle, execute, outcome_error


class ThreadJobExecutor(JobExecutor):
    """``workers`` jobs at a time on a thread pool; a cancelled queued job never starts,
    a running one stops at its next progress check (within about 0.2 s)."""

    client = None  # a dask.distributed.Client handed to the jobs (bsdflab.distributed.executor)

    def __init__(self, workers: int = 1):
        self.workers = workers
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
                              handle.cancel_requested, client=self.client)
            handle._finish(outcome[1] if outcome[0] == "done" else None, outcome_error(outcome))
        finally:
            self._handles.discard(handle)

    def shutdown(self) -> None:
        for handle in list(self._handles):
            handle.cancel()
        self._pool.shutdown(wait=True, cancel_futures=True)
        for handle in list(self._handles):   # queued futures the pool dropped
            handle._finish(error=JobCancelled("executor shut down"))


def _cancel_if_queued(handle: JobHandle) -> None:
    handle._finish(error=JobCancelled("cancelled before it started"), if_queued=True)
