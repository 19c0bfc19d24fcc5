"""The Dask runner: work units on a Dask cluster — submit, collect as they complete, show
progress, cancel on Ctrl-C. It registers itself as the ``"dask"`` runner
(bsdflab.util.runners), so ``tabulate(..., client=)``, ``render(..., client=)`` and the job
executor spec ``dask:<address>`` / ``dask:local:N`` reach it by name: no layer below this one
knows Dask exists.

Faults are Dask's business: units are pure, so a unit lost with a killed worker is simply
recomputed elsewhere (the nanny restarts the worker; the scheduler reschedules its tasks;
``retries`` covers units that raised on a sick worker). The runner only hands results back
as they arrive and never writes a file itself — callers write once, atomically, after the
last unit.
"""
from __future__ import annotations

import contextlib
import signal
import threading
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from distributed import as_completed

from bsdflab.distributed.cluster import connect
from bsdflab.util.progress import JobCancelled, cancel_requested
from bsdflab.util.runners import Runner, finished_unit, progress_bar

# Reruns of a unit that raised (beyond the scheduler's own rescheduling of units whose
# worker died, which `distributed.scheduler.allowed-failures` bounds).
RETRIES = 2
POLL_S = 0.05
# A shared value travels in the graph once, on purpose (its lineage): Dask's advice to use
# futures instead does not apply. A filter set once, at import: catch_warnings() around
# the submit is not thread-safe, and the job server runs several jobs in threads.
warnings.filterwarnings("ignore", message="Sending large graph", category=UserWarning, module="distributed.client")


class DaskRunner(Runner):
    """Units on the workers of ``client`` (a ``distributed.Client``)."""

    name = "dask"

    def __init__(self, client):
        self.client = client

    def workers(self) -> int:
        return len(self.client.scheduler_info().get("workers", {}))

    @classmethod
    @contextlib.contextmanager
    def connect(cls, target: str) -> Iterator[DaskRunner]:
        """``target``: a scheduler address or ``local:N`` (a LocalCluster of N workers)."""
        target = target.strip()
        local = target.startswith("local:")
        with (connect(cluster=target) if local else connect(scheduler=target)) as client:
            yield cls(client)

    def run(self, fn: Callable[..., Any], shared: Sequence[Any], units: Sequence[Any],
            on_result: Callable[[Any, Any], None], *, key: str, desc: str = "units",
            progress: bool = True, progress_callback: Callable[[float], None] | None = None,
            cancelled: Callable[[], bool] | None = None) -> None:
        """``Runner.run`` on the cluster. ``shared`` values are sent once (as tasks that
        return them) instead of with every unit; unit ``i`` is the task ``f"{key}-{i}"``.
        Ctrl-C, a job monitor's cancel or ``cancelled()`` cancel every outstanding unit."""
        client = self.client
        # Each shared value is the result of a task that returns it, not scattered data:
        # a task's result has lineage, so when the worker holding it dies the scheduler
        # computes it again elsewhere, where scattered data would be lost with it (and
        # every unit with FutureCancelledError; Dask's memory manager keeps one copy of a
        # broadcast). Workers fetch it from each other on first use. pure=False: fresh keys.
        shared_futures = [client.submit(_shared_value, v, pure=False) for v in shared]
        futures = [client.submit(fn, *shared_futures, u, key=f"{key}-{i}", retries=RETRIES, pure=False)
                   for i, u in enumerate(units)]
        unit_of = {f.key: u for f, u in zip(futures, units)}
        done = 0
        stop = cancelled or (lambda: False)
        try:
            with progress_bar(len(units), desc, progress) as bar, _sigint_as_flag() as interrupted:
                pending = as_completed(futures)
                while not pending.is_empty():
                    # Poll rather than block on the next unit, so a cancel is seen within
                    # POLL_S even while every outstanding unit is long.
                    if interrupted.is_set():
                        raise KeyboardInterrupt
                    if cancel_requested() or stop():
                        raise JobCancelled(f"{desc} cancelled")
                    batch = pending.next_batch(block=False)
                    if not batch:
                        time.sleep(POLL_S)
                        continue
                    for future in batch:
                        on_result(unit_of[future.key], future.result())
                        future.release()
                        done += 1
                        finished_unit(bar, desc, done / len(units), progress_callback)
        except BaseException:
            client.cancel(futures)
            raise
        finally:
            for f in shared_futures:
                f.release()


def _shared_value(value: Any) -> Any:
    """The task whose result is a job's shared value (recomputed if its holder dies)."""
    return value


@contextlib.contextmanager
def _sigint_as_flag() -> Iterator[threading.Event]:
    """On the main thread, Ctrl-C sets the returned flag instead of raising wherever the
    thread happens to be (inside Dask's client code, a lock or a tqdm refresh): the poll
    loop then raises it at one known place, within POLL_S. A second Ctrl-C raises at once
    (the loop may be held by a slow result or callback), and one the loop never looked at
    is raised on leaving. Elsewhere (a job server's worker thread, or a caller with its own
    SIGINT handler) nothing changes."""
    flag = threading.Event()
    if threading.current_thread() is not threading.main_thread() \
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield flag
        return

    def interrupted(signum, frame) -> None:
        if flag.is_set():
            raise KeyboardInterrupt
        flag.set()

    previous = signal.signal(signal.SIGINT, interrupted)
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)
    if flag.is_set():   # came after the loop's last look (during the last result): not lost
        raise KeyboardInterrupt
