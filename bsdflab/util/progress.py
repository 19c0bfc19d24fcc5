"""Run a long C++ job (tabulation, rendering) with a progress bar and clean Ctrl-C.

The job object needs ``run()`` (releases the GIL), ``cancel()``, ``total`` and ``done``.

A caller that runs the Python API as a job (bsdflab.jobs) installs a *monitor* around the
call with ``monitored(progress, cancelled)``: every C++ job started inside reports
``progress(stage, fraction)`` ("tabulating", "rendering") and stops, raising
``JobCancelled``, once ``cancelled()`` returns True. Code that does its work elsewhere
(a cluster) reports through ``report_progress`` and polls ``cancel_requested``.
"""
from __future__ import annotations

import contextlib
import contextvars
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass


class JobCancelled(Exception):
    """The job was cancelled through its monitor (see ``monitored``)."""


@dataclass(frozen=True)
class Monitor:
    progress: Callable[[str, float], None]   # (stage, fraction of that stage in [0, 1])
    cancelled: Callable[[], bool]


_MONITOR: contextvars.ContextVar[Monitor | None] = contextvars.ContextVar("bsdflab_monitor", default=None)


@contextlib.contextmanager
def monitored(progress: Callable[[str, float], None], cancelled: Callable[[], bool]) -> Iterator[None]:
    """Report the progress of, and allow cancelling, the C++ jobs run in this block
    (this thread or task only: a context variable)."""
    token = _MONITOR.set(Monitor(progress, cancelled))
    try:
        yield
    finally:
        _MONITOR.reset(token)


def report_progress(stage: str, fraction: float) -> None:
    """Tell the active monitor, if any, how far ``stage`` has got."""
    monitor = _MONITOR.get()
    if monitor is not None:
        monitor.progress(stage, min(1.0, max(0.0, float(fraction))))


def cancel_requested() -> bool:
    """True when the active monitor asks the work to stop."""
    monitor = _MONITOR.get()
    return monitor is not None and bool(monitor.cancelled())


def stop_if_cancelled(what: str) -> None:
    """Raise ``JobCancelled`` when the active monitor asks the work to stop (Python loops
    call this once per step: a cancel then waits at most one step)."""
    if cancel_requested():
        raise JobCancelled(f"{what} cancelled")


def run_with_progress(job, show: bool, unit: str, desc: str) -> None:
    """Run the job on a worker thread (the core releases the GIL) while the main thread
    draws the progress bar; Ctrl-C cancels the job, waits for it to stop and re-raises.

    The main thread waits on an Event, not on Thread.join: on CPython < 3.13 a Ctrl-C
    inside join() can mark the still-running thread as finished (python/cpython#90882),
    so a later join() returns at once and the interpreter exits under the running job,
    which aborts the process (SIGABRT from the GIL hand-back at shutdown)."""
    error: list[BaseException] = []
    finished = threading.Event()

    def work():
        try:
            job.run()
        except BaseException as e:  # surfaced on the main thread below
            error.append(e)
        finally:
            finished.set()

    worker = threading.Thread(target=work, name=f"bsdflab-{desc}", daemon=True)
    worker.start()
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=job.total, unit=unit, desc=desc, leave=False)
    monitor = _MONITOR.get()
    try:
        while not finished.wait(0.2):
            if bar is not None:
                bar.n = job.done
                bar.refresh()
            if monitor is not None:
                monitor.progress(desc, job.done / max(job.total, 1))
                if monitor.cancelled():
                    _stop(job, finished)
                    raise JobCancelled(f"{desc} cancelled")
    except KeyboardInterrupt:
        _stop(job, finished)
        raise
    finally:
        if bar is not None:
            bar.close()
    if error:
        raise error[0]
    if monitor is not None:
        monitor.progress(desc, 1.0)


def _stop(job, finished: threading.Event) -> None:
    job.cancel()
    while True:  # the job stops after its current work items; never leave it running
        try:
            finished.wait()
            return
        except KeyboardInterrupt:
            continue
