"""``make_executor``: the job executor a spec (the ``BSDFLAB_EXECUTOR`` setting) names."""
from __future__ import annotations

import os

from bsdflab.jobs.executor import JobExecutor
from bsdflab.jobs.processes import ProcessJobExecutor
from bsdflab.jobs.threads import RunnerJobExecutor, ThreadJobExecutor
from bsdflab.util import args as check
from bsdflab.util.runners import RUNNERS


def default_workers() -> int:
    """One worker per core but one, at most four: each job already uses every core (the C++
    core's threads), so more workers add concurrency, not throughput."""
    return max(1, min(4, (os.cpu_count() or 1) - 1))


def make_executor(spec: str = "processes", workers: int | None = None) -> JobExecutor:
    """The executor named by ``spec`` (the ``BSDFLAB_EXECUTOR`` setting).

    ``"processes"`` (worker processes), ``"threads"`` (threads of this process), or
    ``"<runner>:<target>"``: job drivers on threads here, their work units on that runner
    (bsdflab.util.runners), e.g. ``"dask:<scheduler address>"`` or ``"dask:local:N"``
    (bsdflab.distributed). ``workers``: pool size (default `default_workers`)."""
    workers = default_workers() if workers is None else workers
    workers = check.integer("workers", workers, 1, 1024)
    spec = (spec or "processes").strip()
    if spec == "processes":
        return ProcessJobExecutor(workers)
    if spec == "threads":
        return ThreadJobExecutor(workers)
    name, _, target = spec.partition(":")
    if target and name in RUNNERS.names():
        try:
            RUNNERS.get(name)
        except ImportError as e:
            raise RuntimeError(f"executor {spec!r} needs the {name!r} runner, which could not be "
                               f"imported: {e}") from None
        return RunnerJobExecutor(spec, workers)
    raise ValueError(f"unknown executor {spec!r}; use 'processes', 'threads', "
                     "'dask:<scheduler address>' or 'dask:local:N'")
