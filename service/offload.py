"""Client files read in check worker processes, never in the web process.

An uploaded file (a measured file, a fit data file) is parsed by Python and C++ readers
that hold the GIL for seconds (a 63 MiB .ProcSpec of XML: 8.8 s), and a render material
that names a stored file loads that file to be checked: both run as jobs of the kind
``check`` (bsdflab.service.worker_checks) on their own `ProcessJobExecutor`, the
mechanism of the service's jobs, with ``BSDFLAB_CHECK_WORKERS`` processes started on the
first check. A check waits at most ``BSDFLAB_CHECK_DEADLINE_S`` for a worker and then runs
at most as long (its worker is killed past it), and may grow its worker by
``BSDFLAB_LIMIT_CHECK_MEMORY_BYTES``; one client key has at most
``BSDFLAB_LIMIT_CHECKS_PER_KEY`` checks waiting or running (429 beyond, before queueing).

``Checker.run`` blocks its caller (an upload's thread, which waits without the GIL);
``Checker.run_async`` awaits the check on the event loop, holding no thread. Both answer
the check's summary, or the client's error: the reader's ValueError as it is (a 422 naming
the file), 413 past the memory bound, 422 past the deadline's running time or when the
worker died reading it, 503 when no worker was free within the deadline. Never a 500.
"""
from __future__ import annotations

import asyncio
import collections
import contextlib
import json
import threading
import time
from pathlib import Path
from typing import Any

from fastapi import HTTPException

from bsdflab.jobs import register_kind
from bsdflab.jobs.executor import JobFailed, JobHandle
from bsdflab.jobs.processes import ProcessJobExecutor
from bsdflab.service import worker_checks
from bsdflab.service.errors import cut_message
from bsdflab.service.settings import limit_variable
from bsdflab.util.progress import JobCancelled

register_kind(worker_checks.KIND, worker_checks.__name__)
CLIENT_ERRORS = ("ValueError", "TypeError", "OverflowError")   # the service's 422s (bsdflab.service.errors)
# checks whose passing is kept, by their canonical JSON: their files are named by content hash,
# so the same args pass again (a table check's answer, whether the table exists, changes)
REMEMBERED = ("materials",)
REMEMBERED_MAX = 1024


class Checker:
    def __init__(self, settings, out_dir: Path, folders: dict[str, Path] | None = None):
        """``folders``: server folders a reader's message may name (a table file's path) and
        the words that replace them in an answer."""
        self.settings, self.out_dir, self.folders = settings, out_dir, folders or {}
        self._executor: ProcessJobExecutor | None = None
        self._lock = threading.Lock()
        self._closed = False
        self._in_flight: collections.Counter[str | None] = collections.Counter()   # checks per client key
        self._passed: collections.OrderedDict[str, dict[str, Any]] = collections.OrderedDict()   # REMEMBERED
        self.submitted = 0   # checks sent to a worker (for tests and monitoring)

    def _pool(self) -> ProcessJobExecutor:
        with self._lock:
            if self._closed:
                raise HTTPException(503, "the server is stopping; retry later", headers={"Retry-After": "5"})
            if self._executor is None:   # on the first check: a server that never checks spawns nothing
                self._executor = ProcessJobExecutor(self.settings.check_workers, cancel_grace_s=0.0, warm=False,
                                                    name="bsdflab-check-worker")
            return self._executor

    @contextlib.contextmanager
    def _slot(self, client: str | None):
        """One of ``client``'s BSDFLAB_LIMIT_CHECKS_PER_KEY checks, taken before its check
        is queued (429 when none is free): one key's checks cannot fill the queue that
        every key's uploads wait in. None: not counted."""
        limit = self.settings.limit_checks_per_key
        with self._lock:
            if client is not None and self._in_flight[client] >= limit:
                raise HTTPException(429, f"client {client!r} has {self._in_flight[client]} checks of files waiting "
                                         f"or running, its share ({limit_variable('limit_checks_per_key')}); "
                                         "retry when they end", headers={"Retry-After": "5"})
            self._in_flight[client] += 1
        try:
            yield
        finally:
            with self._lock:
                self._in_flight[client] -= 1
                if self._in_flight[client] <= 0:
                    del self._in_flight[client]

    def _remembered(self, check: str, args: dict[str, Any]) -> tuple[str | None, dict[str, Any] | None]:
        """(the canonical JSON of a REMEMBERED check, its summary when it passed before)."""
        if check not in REMEMBERED:
            return None, None
        name = json.dumps([check, args], sort_keys=True, separators=(",", ":"))
        with self._lock:
            found = self._passed.get(name)
            if found is not None:
                self._passed.move_to_end(name)
        return name, found

    def _remember(self, name: str | None, summary: dict[str, Any]) -> dict[str, Any]:
        if name is not None:
            with self._lock:
                self._passed[name] = summary
                while len(self._passed) > REMEMBERED_MAX:
                    self._passed.popitem(last=False)
        return summary

    def _submit(self, check: str, args: dict[str, Any]) -> JobHandle:
        with self._lock:
            self.submitted += 1
        return self._pool().submit(worker_checks.KIND, {"check": check, "args": args,
                                                        "memory_bytes": self.settings.limit_check_memory_bytes},
                                   self.out_dir)

    def run(self, check: str, args: dict[str, Any], what: str, client: str | None = None) -> dict[str, Any]:
        """The summary of check ``check`` on ``args`` (bsdflab.service.worker_checks);
        ``what`` names the checked thing in an error ("the upload", "options.material");
        ``client``: the key whose share of checks it takes. Blocks this thread."""
        name, found = self._remembered(check, args)
        if found is not None:
            return found
        with self._slot(client):
            handle = self._submit(check, args)
            changed = threading.Event()
            handle.on_change(lambda h: changed.set())

            def wait(done, timeout: float) -> bool:
                end = time.monotonic() + timeout
                while not done():
                    changed.clear()
                    if done():
                        break
                    if not changed.wait(max(0.0, end - time.monotonic())):
                        return done()
                return True

            return self._remember(name, self._answer(handle, what, wait))

    async def run_async(self, check: str, args: dict[str, Any], what: str, client: str | None = None
                        ) -> dict[str, Any]:
        """``run`` awaited on the event loop: the wait holds no thread (a route's thread
        waiting for a queued check was one of the 40 that every sync route shares)."""
        name, found = self._remembered(check, args)
        if found is not None:
            return found
        with self._slot(client):
            handle = self._submit(check, args)
            loop, changed = asyncio.get_running_loop(), asyncio.Event()

            def watcher(h) -> None:   # on the dispatcher's thread: it must never raise there
                try:
                    loop.call_soon_threadsafe(changed.set)
                except RuntimeError:   # the loop is closed
                    pass

            handle.on_change(watcher)

            async def wait(done, timeout: float) -> bool:
                end = time.monotonic() + timeout
                while not done():
                    changed.clear()
                    if done():
                        break
                    try:
                        await asyncio.wait_for(changed.wait(), max(0.0, end - time.monotonic()))
                    except asyncio.TimeoutError:
                        return done()
                return True

            try:
                started = await wait(lambda: handle.state != "queued", self.settings.check_deadline_s)
                finished = started and await wait(handle.done, self._left(handle))
            except BaseException:   # the request was dropped: its check is not wanted
                handle.cancel()
                raise
            return self._remember(name, self._outcome(handle, what, started, finished))

    def _left(self, handle: JobHandle) -> float:
        """What is left of the deadline for a running check: its running time counts, its wait did not."""
        return max(0.0, self.settings.check_deadline_s - handle.progress()[1])

    def _answer(self, handle: JobHandle, what: str, wait) -> dict[str, Any]:
        started = wait(lambda: handle.state != "queued", self.settings.check_deadline_s)
        finished = started and wait(handle.done, self._left(handle))
        return self._outcome(handle, what, started, finished)

    def _outcome(self, handle: JobHandle, what: str, started: bool, finished: bool) -> dict[str, Any]:
        """The check's summary, or the client's error. A check that waited out the deadline
        for a worker is a 503 (the server is busy); one that ran past it is a 422 (its file)."""
        s = self.settings
        if not started:
            handle.cancel()
            raise HTTPException(503, f"all {s.check_workers} check workers ({limit_variable('check_workers')}) "
                                     f"stayed busy for {s.check_deadline_s:g} s "
                                     f"({limit_variable('check_deadline_s')}); retry later",
                                headers={"Retry-After": "5"})
        if not finished:
            handle.cancel()   # a running check's worker is killed (its reader does not look)
            raise HTTPException(422, f"{what}: reading it took longer than {s.check_deadline_s:g} s "
                                     f"({limit_variable('check_deadline_s')})")
        try:
            return handle.result(0)
        except JobCancelled:
            raise HTTPException(503, "the server is stopping; retry later", headers={"Retry-After": "5"}) from None
        except JobFailed as e:
            if e.error_type in CLIENT_ERRORS:
                raise ValueError(self._public(str(e))) from None   # the reader's own message
            if e.error_type == "MemoryError":
                raise HTTPException(413, f"{what}: reading it needs more than {s.limit_check_memory_bytes} bytes "
                                         f"of memory ({limit_variable('limit_check_memory_bytes')})") from None
            if e.error_type == "WorkerStartFailed":   # the server's trouble (EMFILE, ENOMEM), not the file's
                raise HTTPException(503, "no check worker could be started; retry later",
                                    headers={"Retry-After": "5"}) from None
            if e.error_type == "WorkerDied":
                raise HTTPException(422, f"{what}: the process reading it stopped ({cut_message(str(e))}); "
                                         "the file cannot be read here") from None
            raise HTTPException(422, f"{what}: could not be read ({e.error_type})") from None

    def _public(self, message: str) -> str:
        """No server folder in an answer (a stored table is loaded by its path)."""
        for folder, word in sorted(self.folders.items(), key=lambda kv: -len(str(kv[0]))):
            message = message.replace(str(folder), word)
        return message

    def worker_pids(self) -> list[int]:
        with self._lock:
            return [] if self._executor is None else self._executor.worker_pids()

    def close(self) -> None:
        with self._lock:
            self._closed, executor = True, self._executor
        if executor is not None:
            executor.shutdown()
