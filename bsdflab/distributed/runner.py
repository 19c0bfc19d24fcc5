"""The Dask runner: work units on a Dask cluster — submit, collect as they complete, show
progress, cancel on Ctrl-C. It registers itself as the ``"dask"`` runner
(bsdflab.util.runners), so ``tabulate(..., client=)``, ``render(..., client=)`` and the job
executor spec ``dask:<address>`` / ``dask:local:N`` reach it by name: no layer below this one
knows Dask exists.

Faults are mostly Dask's business: units are pure, so a unit lost with a killed worker is
simply recomputed elsewhere (the nanny restarts the worker; the scheduler reschedules its
tasks; ``retries`` covers units that raised on a sick worker). The one fault Dask cannot
repair is the loss of every copy of the scattered inputs (they came from this client): the
runner then scatters them again and resubmits the units still missing. The runner only hands results back
as they arrive and never writes a file itself — callers write once, atomically, after the
last unit.
"""
from __future__ import annotations

import contextlib
import logging
import signal
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import CancelledError
from typing import Any

from distributed import as_completed

from bsdflab.distributed.cluster import connect
from bsdflab.util.progress import JobCancelled, cancel_requested
from bsdflab.util.runners import Runner, finished_unit, progress_bar

# Reruns of a unit that raised (beyond the scheduler's own rescheduling of units whose
# worker died, which `distributed.scheduler.allowed-failures` bounds).
RETRIES = 2
# Resubmissions after every worker holding the job's scattered inputs died (see run()).
LOST_DATA_ROUNDS = 3
WORKERS_BACK_S = 120.0   # how long a resubmission waits for a worker (nannies restart theirs)
WAIT_SLICE_S = 0.5       # ... in slices, so Ctrl-C is seen meanwhile
POLL_S = 0.05

log = logging.getLogger(__name__)


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
        """``Runner.run`` on the cluster. ``shared`` values are scattered once (broadcast)
        instead of being sent with every unit; unit ``i`` is the task ``f"{key}-{i}"``.
        Ctrl-C, a job monitor's cancel or ``cancelled()`` cancel every outstanding unit.
        If every worker holding the scattered values dies, Dask cannot recompute them (they
        came from this client) and cancels the units that need them: those units are
        resubmitted with the values scattered again, at most LOST_DATA_ROUNDS times."""
        todo = dict(enumerate(units))
        stop = cancelled or (lambda: False)
        with progress_bar(len(units), desc, progress) as bar, _sigint_as_flag() as interrupted:
            progress_state = _Progress(bar, desc, len(units), progress_callback)
            for round_ in range(LOST_DATA_ROUNDS + 1):
                prefix = key if round_ == 0 else f"{key}-again{round_}"
                if round_:
                    self._await_a_worker(interrupted, stop, desc)
                self._round(fn, shared, todo, on_result, prefix, progress_state, interrupted, stop, desc)
                if not todo:
                    return
                log.warning("%s: the cluster lost the scattered inputs of %d units (their workers died); "
                            "scattering them again", desc, len(todo))
        raise RuntimeError(f"{desc}: the cluster lost the job's scattered inputs {LOST_DATA_ROUNDS + 1} times "
                           f"({len(todo)} units left): workers keep dying")

    def _await_a_worker(self, interrupted: threading.Event, stop: Callable[[], bool], desc: str) -> None:
        """After workers died: wait, still interruptible and cancellable, for one to scatter to."""
        deadline = time.monotonic() + WORKERS_BACK_S
        while True:
            if interrupted.is_set():
                raise KeyboardInterrupt
            if cancel_requested() or stop():
                raise JobCancelled(f"{desc} cancelled")
            try:
                self.client.wait_for_workers(1, timeout=WAIT_SLICE_S)
                return
            except TimeoutError:
                if time.monotonic() > deadline:
                    raise RuntimeError(f"no Dask worker came back within {WORKERS_BACK_S:g} s "
                                       "after the job's workers died") from None

    def _round(self, fn, shared, todo: dict, on_result, prefix: str, progress_state: _Progress,
               interrupted: threading.Event, stop: Callable[[], bool], desc: str) -> None:
        """Submit the units of ``todo`` once and collect them, removing each one that
        returns; units cancelled because their scattered inputs were lost stay in ``todo``."""
        client = self.client
        # Wrapped in a list: scatter() would take a dict's items as separate pieces of data.
        # Fresh keys (hash=False): a content-hash key shared with an earlier, just-released
        # scatter of the same value could be forgotten under this job ("lost dependencies").
        shared_futures = [client.scatter([v], broadcast=True, hash=False)[0] for v in shared]
        futures = [client.submit(fn, *shared_futures, u, key=f"{prefix}-{i}", retries=RETRIES, pure=False)
                   for i, u in todo.items()]
        index_of = {f.key: i for f, i in zip(futures, todo)}
        try:
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
                    try:
                        value = future.result()
                    except CancelledError:   # not by this loop: its inputs were lost
                        continue
                    i = index_of[future.key]
                    on_result(todo.pop(i), value)
                    future.release()
                    progress_state.advance()
        except BaseException:
            client.cancel(futures)
            raise
        finally:
            for f in shared_futures:
                f.release()


class _Progress:
    """Units finished so far, across resubmission rounds, shown on one bar."""

    def __init__(self, bar, desc: str, total: int, callback: Callable[[float], None] | None):
        self.bar, self.desc, self.total, self.callback, self.done = bar, desc, total, callback, 0

    def advance(self) -> None:
        self.done += 1
        finished_unit(self.bar, self.desc, self.done / self.total, self.callback)


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
