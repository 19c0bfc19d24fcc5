"""Where jobs run: the executor interface and the job handle (``make_executor`` in
bsdflab.jobs.factory picks an implementation by name).

``JobExecutor.submit(kind, request, out_dir)`` starts a job of a registered kind
(bsdflab.jobs.kinds) on a normalised request and returns a ``JobHandle`` at once. Three
implementations: ``ThreadJobExecutor`` (in this process), ``ProcessJobExecutor`` (worker
processes: what the service uses) and ``RunnerJobExecutor`` (drivers on threads here, their
work units on a runner registered by name in bsdflab.util.runners, e.g. ``dask``, which
bsdflab.distributed registers).
"""
from __future__ import annotations

import abc
import os
import threading
import time
import traceback
import uuid
from pathlib import Path
from typing import Any

from bsdflab.jobs.kinds import get_kind
from bsdflab.util.progress import JobCancelled

STATES = ("queued", "running", "done", "failed", "cancelled")
FINISHED = ("done", "failed", "cancelled")


class JobFailed(Exception):
    """The job raised; ``error_type`` names the exception class (e.g. ``ValueError``) and
    ``details`` holds its traceback text."""

    def __init__(self, message: str, error_type: str = "Exception", details: str = ""):
        super().__init__(message)
        self.error_type = error_type
        self.details = details


class JobHandle:
    """One submitted job; every method is thread-safe.

    Executors drive it through ``_started``, ``_progress`` and ``_finish``; callers read it
    with ``state``, ``progress()``, ``done()`` and ``result()``, and may ``cancel()``.
    """

    def __init__(self, kind: str, request: dict[str, Any], out_dir: str | os.PathLike):
        self.id = uuid.uuid4().hex
        self.kind, self.request, self.out_dir = kind, request, Path(out_dir)
        self._lock = threading.Lock()
        self._finished = threading.Event()
        self._cancel = threading.Event()
        self._state = "queued"
        self._fraction = 0.0
        self._start: float | None = None
        self._end: float | None = None
        self._result: dict[str, Any] | None = None
        self._error: BaseException | None = None
        self._on_cancel = None   # set by the executor: called once when cancel() is asked
        self._watchers: list = []   # called after it starts and after it finishes (on_change)

    # -- what callers use ------------------------------------------------------------------
    @property
    def state(self) -> str:
        """One of STATES."""
        with self._lock:
            return self._state

    def progress(self) -> tuple[float, float, float | None]:
        """(fraction done in [0, 1], seconds since the job started, ETA in seconds or None).

        The ETA assumes the rest goes at the average pace so far; None before any progress."""
        with self._lock:
            if self._start is None:
                return self._fraction, 0.0, None
            elapsed = (self._end if self._end is not None else time.monotonic()) - self._start
            f = self._fraction
            if self._state in FINISHED:
                return f, elapsed, 0.0 if self._state == "done" else None
            eta = elapsed * (1.0 - f) / f if f > 0 else None
            return f, elapsed, eta

    def cancel(self) -> bool:
        """Ask the job to stop. False when it had already finished (done or failed)."""
        with self._lock:
            if self._state in FINISHED:
                return self._state == "cancelled"
            first = not self._cancel.is_set()
            self._cancel.set()
            hook = self._on_cancel
        if first and hook is not None:
            hook(self)
        return True

    def cancel_requested(self) -> bool:
        return self._cancel.is_set()

    def done(self) -> bool:
        return self._finished.is_set()

    def result(self, timeout: float | None = None) -> dict[str, Any]:
        """The job's result; raises JobCancelled or JobFailed, or TimeoutError if it is
        still running after ``timeout`` seconds."""
        if not self._finished.wait(timeout):
            raise TimeoutError(f"job {self.id} still {self.state} after {timeout} s")
        if self._error is not None:
            raise self._error
        return self._result

    def on_change(self, watcher) -> None:
        """Call ``watcher(self)`` after the job starts and after it finishes (on the
        executor's thread; once at once when it has started already), so that an event loop
        can wait for it without a thread."""
        with self._lock:
            self._watchers.append(watcher)
            now = self._state != "queued"
        if now:
            watcher(self)

    def _changed(self) -> None:
        with self._lock:
            watchers = list(self._watchers)
        for watcher in watchers:
            watcher(self)

    def error(self) -> BaseException | None:
        """The exception of a failed or cancelled job (None otherwise)."""
        return self._error if self._finished.is_set() else None

    # -- what executors use ------------------------------------------------------------------
    def _started(self) -> bool:
        """Queued -> running; False when the job is no longer queued (cancelled meanwhile)."""
        with self._lock:
            if self._state != "queued":
                return False
            self._state, self._start = "running", time.monotonic()
        self._changed()
        return True

    def _progress(self, fraction: float) -> None:
        with self._lock:
            if self._state == "running":
                self._fraction = max(self._fraction, min(1.0, max(0.0, float(fraction))))

    def _finish(self, result: dict[str, Any] | None = None, error: BaseException | None = None,
                if_queued: bool = False) -> bool:
        """Done with ``result``, failed with ``error``, or cancelled (error a JobCancelled);
        with ``if_queued`` only a job that has not started. True when this call finished it."""
        with self._lock:
            if self._state in FINISHED or (if_queued and self._state != "queued"):
                return False
            now = time.monotonic()
            self._start = now if self._start is None else self._start
            self._end = now
            if error is None:
                self._state, self._result, self._fraction = "done", result, 1.0
            else:
                self._state = "cancelled" if isinstance(error, JobCancelled) else "failed"
                self._error = error
        self._finished.set()
        self._changed()
        return True


def execute(kind: str, request: dict[str, Any], out_dir, progress, cancelled, runner=None):
    """Run one job here: ("done", result), ("cancelled", message) or
    ("failed", error type, message, traceback text). Never raises (executors turn this into
    the handle's outcome, possibly in another process)."""
    try:
        if cancelled():
            return ("cancelled", "cancelled before it started")
        result = get_kind(kind).run(request, Path(out_dir), progress, cancelled, runner=runner)
        return ("done", result)
    except JobCancelled as e:
        return ("cancelled", str(e) or "cancelled")
    except BaseException as e:  # noqa: BLE001 -- reported to the caller, not lost
        return ("failed", type(e).__name__, str(e) or type(e).__name__, traceback.format_exc())


def outcome_error(outcome: tuple) -> BaseException | None:
    """The exception (or None for "done") a handle finishes with, from ``execute``'s tuple."""
    if outcome[0] == "done":
        return None
    if outcome[0] == "cancelled":
        return JobCancelled(outcome[1])
    return JobFailed(outcome[2], outcome[1], outcome[3] if len(outcome) > 3 else "")


class JobExecutor(abc.ABC):
    """Runs jobs; ``submit`` returns at once."""

    workers: int = 1

    @abc.abstractmethod
    def submit(self, kind: str, request: dict[str, Any], out_dir: str | os.PathLike) -> JobHandle:
        """Start (or queue) a job of ``kind`` on a normalised ``request``, writing its
        artefacts into ``out_dir``."""

    @abc.abstractmethod
    def shutdown(self) -> None:
        """Stop: queued jobs are cancelled, running ones interrupted. Idempotent."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.shutdown()
