"""Where distributed work runs: a Dask scheduler address, or a LocalCluster of N processes.

The engine is Dask distributed, unchanged: ``dask scheduler`` / ``dask worker`` on a
cluster, dask-jobqueue on SLURM/PBS, dask-kubernetes in the cloud. bsdflab only connects a
``Client`` and sends it pure work units (docs/distributed.md).
"""
from __future__ import annotations

import contextlib
import logging
import os
import re
import signal
from collections.abc import Iterator

from distributed import Client, LocalCluster

from bsdflab.util.settings import library_settings

_LOCAL = re.compile(r"^local:(\d+)$")
MAX_LOCAL_WORKERS = 256


def parse_cluster(spec: str) -> int:
    """The worker count of ``"local:N"``; ValueError for anything else."""
    m = _LOCAL.match(spec.strip()) if isinstance(spec, str) else None
    if not m or not 1 <= int(m.group(1)) <= MAX_LOCAL_WORKERS:
        raise ValueError(f"cluster must be 'local:N' with 1 <= N <= {MAX_LOCAL_WORKERS}, got {spec!r}")
    return int(m.group(1))


def check_scheduler_address(address: str) -> str:
    """A scheduler address (``tcp://host:port``, ``tls://...``, ``inproc://...``) or ValueError."""
    if not isinstance(address, str) or not re.match(r"^(tcp|tls|ucx|inproc|ws|wss)://\S+$", address.strip()):
        raise ValueError(f"scheduler must be an address like tcp://HOST:8786, got {address!r}")
    return address.strip()


def local_cluster(n_workers: int, threads_per_worker: int | None = None):
    """A LocalCluster of ``n_workers`` worker processes (each under a nanny, so a killed
    worker is restarted and its units rescheduled). Each worker's C++ core uses
    ``threads_per_worker`` threads (default: the machine's cores shared out), so N workers
    do not oversubscribe the machine."""
    cores = os.cpu_count() or 1
    threads = threads_per_worker or max(1, cores // n_workers)
    # One Dask thread per worker (one unit at a time); the unit itself uses `threads` C++
    # threads through BSDFLAB_THREADS, read by the core when the worker imports it.
    return LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                        dashboard_address=None, env={"BSDFLAB_THREADS": str(threads)},
                        silence_logs=logging.ERROR)


@contextlib.contextmanager
def connect(scheduler: str | None = None, cluster: str | None = None,
            timeout: float | None = None) -> Iterator[object]:
    """A ``distributed.Client`` for ``scheduler`` (an address) or ``cluster`` ("local:N"),
    closed (and the local cluster shut down) on exit.

    Raises ValueError for a malformed argument and ConnectionError naming the address when
    no scheduler answers within ``timeout`` seconds (default BSDFLAB_CONNECT_TIMEOUT_S, 10) —
    before any work is sent.
    """
    if (scheduler is None) == (cluster is None):
        raise ValueError("give exactly one of scheduler (an address) or cluster ('local:N')")
    if cluster is not None:
        with local_cluster(parse_cluster(cluster)) as lc, Client(lc) as client:
            try:
                yield client
            except BaseException:
                _kill_workers(lc)
                raise
        return
    address = check_scheduler_address(scheduler)
    if timeout is None:   # an unreachable address must fail before any work, naming it
        timeout = library_settings().connect_timeout_s
    try:
        client = Client(address, timeout=timeout)
    except (OSError, TimeoutError) as e:
        raise ConnectionError(f"no Dask scheduler answers at {address} (waited {timeout:g} s): {e}") from None
    try:
        yield client
    finally:
        client.close()


def _kill_workers(lc) -> None:
    """Kill a local cluster's worker processes before it closes, after a failure or Ctrl-C.
    A unit in the C++ core cannot be cancelled, and a graceful close waits for it (seconds
    under load); the workers hold nothing worth keeping (units are pure, results already
    came back), so the close is then immediate and Ctrl-C's latency bounded."""
    for nanny in list(getattr(lc, "workers", {}).values()):
        # First tell the nanny not to restart its worker (it would spawn a new one, which
        # the close then waits for); close_gracefully only sets that status.
        with contextlib.suppress(Exception):
            nanny.close_gracefully(reason="bsdflab-interrupted")
        process = getattr(getattr(nanny, "process", None), "process", None)
        pid = getattr(process, "pid", None)
        if pid:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, signal.SIGKILL)
