"""Client files read in check worker processes, never in the web process.

An uploaded file (a measured file, a fit data file) is parsed by Python and C++ readers
that hold the GIL for seconds (a 63 MiB .ProcSpec of XML: 8.8 s), and a render material
that names a stored file loads that file to be checked: both run as jobs of the kind
``check`` (bsdflab.service.worker_checks) on their own `ProcessJobExecutor`, the
mechanism of the service's jobs, with ``BSDFLAB_CHECK_WORKERS`` processes started on the
first check. Each check has ``BSDFLAB_CHECK_DEADLINE_S`` from its submission (its worker is
killed past it) and may grow its worker by ``BSDFLAB_LIMIT_CHECK_MEMORY_BYTES``.

``Checker.run`` blocks its caller (a route's thread, which waits without the GIL) and
answers the check's summary, or the client's error: the reader's ValueError as it is (a
422 naming the file), 413 past the memory bound, 422 past the deadline or when the worker
died reading it, 503 when every worker stayed busy until the deadline. Never a 500.
"""
from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

from fastapi import HTTPException

from bsdflab.jobs import register_kind
from bsdflab.jobs.executor import JobFailed
from bsdflab.jobs.processes import ProcessJobExecutor
from bsdflab.service import worker_checks
from bsdflab.service.errors import cut_message
from bsdflab.service.settings import limit_variable
from bsdflab.util.progress import JobCancelled

register_kind(worker_checks.KIND, worker_checks.__name__)
CLIENT_ERRORS = ("ValueError", "TypeError", "OverflowError")   # the service's 422s (bsdflab.service.errors)


class Checker:
    def __init__(self, settings, out_dir: Path, folders: dict[str, Path] | None = None):
        """``folders``: server folders a reader's message may name (a table file's path) and
        the words that replace them in an answer."""
        self.settings, self.out_dir, self.folders = settings, out_dir, folders or {}
        self._executor: ProcessJobExecutor | None = None
        self._lock = threading.Lock()
        self._closed = False

    def _pool(self) -> ProcessJobExecutor:
        with self._lock:
            if self._closed:
                raise HTTPException(503, "the server is stopping; retry later", headers={"Retry-After": "5"})
            if self._executor is None:   # on the first check: a server that never checks spawns nothing
                self._executor = ProcessJobExecutor(self.settings.check_workers, cancel_grace_s=0.0, warm=False,
                                                    name="bsdflab-check-worker")
            return self._executor

    def run(self, check: str, args: dict[str, Any], what: str) -> dict[str, Any]:
        """The summary of check ``check`` on ``args`` (bsdflab.service.worker_checks);
        ``what`` names the checked thing in an error ("the upload", "options.material")."""
        s = self.settings
        handle = self._pool().submit(worker_checks.KIND, {"check": check, "args": args,
                                                          "memory_bytes": s.limit_check_memory_bytes}, self.out_dir)
        try:
            return handle.result(s.check_deadline_s)
        except TimeoutError:
            started = handle.state == "running"
            handle.cancel()   # a running check's worker is killed (its reader does not look)
            if started:
                raise HTTPException(422, f"{what}: reading it took longer than {s.check_deadline_s:g} s "
                                         f"({limit_variable('check_deadline_s')})") from None
            raise HTTPException(503, f"all {s.check_workers} check workers ({limit_variable('check_workers')}) "
                                     f"stayed busy for {s.check_deadline_s:g} s "
                                     f"({limit_variable('check_deadline_s')}); retry later",
                                headers={"Retry-After": "5"}) from None
        except JobCancelled:
            raise HTTPException(503, "the server is stopping; retry later", headers={"Retry-After": "5"}) from None
        except JobFailed as e:
            if e.error_type in CLIENT_ERRORS:
                raise ValueError(self._public(str(e))) from None   # the reader's own message
            if e.error_type == "MemoryError":
                raise HTTPException(413, f"{what}: reading it needs more than {s.limit_check_memory_bytes} bytes "
                                         f"of memory ({limit_variable('limit_check_memory_bytes')})") from None
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
