"""The service's jobs on a Dask cluster (``BSDFLAB_EXECUTOR=dask:tcp://HOST:8786`` or
``dask:local:N``).

A job's driver — the same job function the other executors run — runs on a thread of the
service process with this executor's ``Client``; its work units go to the cluster
(bsdflab.distributed). Progress and cancellation reach the units through the job monitor
(bsdflab.util.progress): the unit driver reports each finished unit and cancels the outstanding
ones when the job is cancelled.
"""
from __future__ import annotations

from bsdflab.jobs.threads import ThreadJobExecutor
from bsdflab.distributed.cluster import connect


class DaskJobExecutor(ThreadJobExecutor):
    """``workers`` concurrent job drivers sharing one cluster connection."""

    def __init__(self, target: str, workers: int = 1):
        target = target.strip()
        local = target.startswith("local:")
        self._connection = connect(cluster=target) if local else connect(scheduler=target)
        self.client = self._connection.__enter__()  # ConnectionError before any job is accepted
        super().__init__(workers)

    def shutdown(self) -> None:
        try:
            super().shutdown()
        finally:
            if self._connection is not None:
                self._connection.__exit__(None, None, None)
                self._connection = None
