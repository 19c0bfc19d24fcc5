"""Jobs in worker processes: a pool of at most ``workers`` spawned processes.

One dispatcher thread owns every worker: it hands a queued job to an idle worker over
that worker's pipe, reads progress and outcomes back, sets the worker's cancel event
when a job is cancelled (and kills the worker if the job has not stopped within
``cancel_grace_s``), and replaces workers that die. Workers start on demand (the first
at once) and die with the process that owns them (``PR_SET_PDEATHSIG`` and a parent
check), so a killed server leaves no job running behind it.
"""
from __future__ import annotations

import collections
import multiprocessing
import multiprocessing.connection
import os
import threading
import time
from typing import Any

from bsdflab.jobs.executor import JobExecutor, JobFailed, JobHandle, execute, outcome_error
from bsdflab.jobs.kinds import module_of
from bsdflab.util.progress import JobCancelled

PROGRESS_INTERVAL_S = 0.1   # at most ten progress messages a second per worker
POLL_S = 0.5
SPAWN_BACKOFF_S = 0.1       # after a worker failed to start: the first wait before the next try
SPAWN_BACKOFF_MAX_S = 5.0   # the longest


class _Worker:
    def __init__(self, ctx, number: int, warm: bool = True, name: str = "bsdflab-job-worker"):
        self.conn, child = ctx.Pipe()
        self.cancel = ctx.Event()
        self.process = ctx.Process(target=worker_main, args=(child, self.cancel, os.getpid(), warm),
                                   name=f"{name}-{number}", daemon=True)
        self.process.start()
        child.close()
        self.ready = False
        self.handle: JobHandle | None = None
        self.cancel_sent_at: float | None = None

    @property
    def idle(self) -> bool:
        return self.ready and self.handle is None


class ProcessJobExecutor(JobExecutor):
    """Run jobs in up to ``workers`` worker processes (started with ``spawn``). ``warm``:
    workers import every kind's module at start (`warm_up`); a pool that runs one small
    kind (the service's upload checks) starts faster without."""

    def __init__(self, workers: int = 1, cancel_grace_s: float = 10.0, warm: bool = True,
                 name: str = "bsdflab-job-worker"):
        self.workers = workers
        self.cancel_grace_s = cancel_grace_s
        self.warm, self.name = warm, name
        self._ctx = multiprocessing.get_context("spawn")
        self._lock = threading.Lock()
        self._pending: collections.deque[JobHandle] = collections.deque()
        self._pool: list[_Worker] = []
        self._spawned = 0
        self._backoff, self._retry_at = 0.0, None   # after a failed worker start (_spawn)
        self._stopping = False
        self._wake_r, self._wake_w = self._ctx.Pipe(duplex=False)
        self._thread = threading.Thread(target=self._loop, name="bsdflab-job-dispatcher", daemon=True)
        self._thread.start()

    # -- the interface ---------------------------------------------------------------------
    def submit(self, kind: str, request: dict[str, Any], out_dir) -> JobHandle:
        handle = JobHandle(kind, request, out_dir)
        handle._on_cancel = lambda h: self._wake()
        with self._lock:
            if self._stopping:
                raise RuntimeError("the executor is shut down")
            self._pending.append(handle)
        self._wake()
        return handle

    def shutdown(self) -> None:
        with self._lock:
            if self._stopping:
                return
            self._stopping = True
        self._wake()
        self._thread.join()

    def worker_pids(self) -> list[int]:
        """Process ids of the live workers (for tests and monitoring)."""
        with self._lock:
            return [w.process.pid for w in self._pool if w.process.pid is not None]

    # -- the dispatcher thread ---------------------------------------------------------
    def _wake(self) -> None:
        with self._lock:
            try:
                self._wake_w.send_bytes(b"!")
            except OSError:   # shut down: the pipe is closed
                pass

    def _loop(self) -> None:
        try:
            self._spawn()
            while True:
                with self._lock:
                    if self._stopping:
                        break
                self._dispatch()
                self._apply_cancels()
                waitables = [self._wake_r] + [w.conn for w in self._pool] + [w.process.sentinel for w in self._pool]
                timeout = POLL_S if self._retry_at is None else min(POLL_S, max(0.0, self._retry_at - time.monotonic()))
                for ready in multiprocessing.connection.wait(waitables, timeout=timeout):
                    self._on_ready(ready)
        finally:
            self._stop_all()

    def _spawn(self) -> None:
        """Start a worker. When the start fails (fork/spawn's OSError: EMFILE, EAGAIN,
        ENOMEM), the job that waited for it fails with that error and the next start waits a
        back-off (doubling, at most SPAWN_BACKOFF_MAX_S): the dispatcher lives on, and later
        jobs run once a start succeeds."""
        if self._retry_at is not None and time.monotonic() < self._retry_at:
            return
        self._spawned += 1
        try:
            worker = _Worker(self._ctx, self._spawned, self.warm, self.name)
        except Exception as e:   # noqa: BLE001 - whatever the start raised, the loop must go on
            self._backoff = min(SPAWN_BACKOFF_MAX_S, 2 * self._backoff) if self._backoff else SPAWN_BACKOFF_S
            self._retry_at = time.monotonic() + self._backoff
            with self._lock:
                waiting = self._pending.popleft() if self._pending else None
            if waiting is not None:
                waiting._finish(error=JobFailed(f"could not start a worker process ({type(e).__name__}: {e}); "
                                                f"retrying in {self._backoff:g} s", "WorkerStartFailed"))
            return
        self._backoff, self._retry_at = 0.0, None
        with self._lock:
            self._pool.append(worker)

    def _dispatch(self) -> None:
        while True:
            with self._lock:
                while self._pending and self._pending[0].cancel_requested():
                    self._pending.popleft()._finish(error=JobCancelled("cancelled before it started"))
                if not self._pending:
                    return
                idle = next((w for w in self._pool if w.idle), None)
                if idle is None:
                    starting = any(not w.ready for w in self._pool)
                    room = len(self._pool) < self.workers
                    if room and not starting:
                        break   # spawn below, outside the lock
                    return
                handle = self._pending.popleft()
            if not handle._started():
                continue
            idle.cancel.clear()
            idle.handle, idle.cancel_sent_at = handle, None
            try:
                idle.conn.send(("run", handle.kind, module_of(handle.kind), handle.request, str(handle.out_dir)))
            except (OSError, ValueError) as e:   # the worker just died; its sentinel says so
                handle._finish(error=JobFailed(f"could not reach the worker: {e}", "OSError"))
                idle.handle = None
        self._spawn()

    def _apply_cancels(self) -> None:
        now = time.monotonic()
        for w in list(self._pool):
            if w.handle is None or not w.handle.cancel_requested():
                continue
            if w.cancel_sent_at is None:
                w.cancel.set()
                w.cancel_sent_at = now
            elif now - w.cancel_sent_at > self.cancel_grace_s:
                w.process.kill()   # did not stop in time; its sentinel finishes the job

    def _on_ready(self, ready) -> None:
        if ready is self._wake_r:
            while self._wake_r.poll():
                self._wake_r.recv_bytes()
            return
        for w in list(self._pool):
            if ready is w.conn:
                try:
                    message = w.conn.recv()
                except (EOFError, OSError):
                    self._retire(w)
                    return
                self._on_message(w, message)
                return
            if ready == w.process.sentinel:
                self._retire(w)
                return

    def _on_message(self, w: _Worker, message: tuple) -> None:
        tag = message[0]
        if tag == "ready":
            w.ready = True
        elif tag == "progress" and w.handle is not None:
            w.handle._progress(message[1])
        elif tag == "outcome" and w.handle is not None:
            outcome = message[1]
            w.handle._finish(outcome[1] if outcome[0] == "done" else None, outcome_error(outcome))
            w.handle = None

    def _retire(self, w: _Worker) -> None:
        """A worker exited (crashed, or killed after a cancel): finish its job, drop it."""
        w.process.join(timeout=5)
        if w.handle is not None:
            if w.handle.cancel_requested():
                w.handle._finish(error=JobCancelled("cancelled (the worker was stopped)"))
            else:
                w.handle._finish(error=JobFailed(
                    f"the worker process died (exit code {w.process.exitcode}) while running the job",
                    "WorkerDied"))
        w.conn.close()
        with self._lock:
            self._pool.remove(w)

    def _stop_all(self) -> None:
        with self._lock:
            pending, self._pending = list(self._pending), collections.deque()
            pool = list(self._pool)
        for handle in pending:
            handle._finish(error=JobCancelled("executor shut down"))
        for w in pool:
            # A worker with a job, or one still starting (its imports can take seconds and
            # it reads no message before they end): killed, as neither has anything to lose.
            # An idle ready worker is told to stop and exits at once.
            if w.handle is not None or not w.ready:
                w.process.kill()
            else:
                try:
                    w.conn.send(("stop",))
                except (OSError, ValueError):
                    pass
        for w in pool:
            w.process.join(timeout=5)
            if w.process.is_alive():
                w.process.kill()
                w.process.join(timeout=5)
            if w.handle is not None:
                w.handle._finish(error=JobCancelled("executor shut down"))
            w.conn.close()
        with self._lock:
            self._pool.clear()
            self._wake_w.close()
        self._wake_r.close()


# -- the worker process ----------------------------------------------------------------------
def _die_with_parent() -> None:
    """Ask Linux to SIGKILL this process when the thread that started it exits."""
    try:
        import ctypes
        import signal

        libc = ctypes.CDLL(None, use_errno=True)
        PR_SET_PDEATHSIG = 1
        libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    except (OSError, AttributeError):   # not Linux: the parent check below still applies
        pass


def worker_main(conn, cancel, parent_pid: int, warm: bool = True) -> None:
    """Serve jobs from ``conn`` until told to stop or the parent goes away."""
    _die_with_parent()
    if os.getppid() != parent_pid:
        return
    from bsdflab.jobs.kinds import register_kind, warm_up

    if warm:
        warm_up()

    def orphaned() -> bool:
        return os.getppid() != parent_pid

    conn.send(("ready",))
    while True:
        try:
            while not conn.poll(1.0):
                if orphaned():
                    return
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message[0] != "run":
            return
        _, kind, module, request, out_dir = message
        register_kind(kind, module)
        last = [0.0]

        def progress(fraction: float, *, last=last) -> None:
            now = time.monotonic()
            if now - last[0] >= PROGRESS_INTERVAL_S:
                last[0] = now
                conn.send(("progress", float(fraction)))

        outcome = execute(kind, request, out_dir, progress, lambda: cancel.is_set() or orphaned())
        try:
            conn.send(("outcome", outcome))
        except (OSError, ValueError):
            return
        except Exception as e:   # an unpicklable result: report it instead of the result
            conn.send(("outcome", ("failed", type(e).__name__, f"the job's result cannot be sent back: {e}", "")))
