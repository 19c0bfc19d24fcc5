"""The service's job manager: the SQLite store, the artefact folder and an executor.

A request is normalised by its kind (bsdflab.jobs), hashed, and then either answered from
the artefact folder (already computed), joined to the active job with the same hash
(dedup), or stored as a new queued job and submitted. A monitor thread copies progress
and outcomes from the executor's handles into the store. On start, jobs a previous
server left queued or running are re-queued (their artefacts are written atomically, so
nothing half-written is ever found). Stopping leaves unfinished jobs in the store for the
next start, exactly as a crash would.
"""
from __future__ import annotations

import logging
import threading
from pathlib import Path
from typing import Any

from bsdflab.jobs import JobHandle, get_kind, make_executor

from bsdflab.service.settings import Settings
from bsdflab.service.store import JobStore

log = logging.getLogger("bsdflab.service")
MAX_ATTEMPTS = 3   # a job that a restart finds unfinished this often has killed its server


class JobService:
    def __init__(self, settings: Settings):
        self.settings = settings
        self.artefact_dir: Path = settings.artefact_dir
        self.artefact_dir.mkdir(parents=True, exist_ok=True)
        self.store = JobStore(settings.db_path)
        self.executor = make_executor(settings.executor, settings.workers)
        self._handles: dict[str, JobHandle] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._recover()
        self._monitor = threading.Thread(target=self._watch, name="bsdflab-job-monitor", daemon=True)
        self._monitor.start()

    # -- submitting --------------------------------------------------------------------------
    def prepare(self, kind: str, request: dict[str, Any]) -> tuple[dict[str, Any], str]:
        """(normalised request, content hash); ValueError for a bad request."""
        k = get_kind(kind)
        normalised = k.normalise(request)
        return normalised, k.key(normalised)

    def cached(self, kind: str, content_hash: str) -> dict[str, Any] | None:
        """The stored result for this hash when its files are all present."""
        row = self.store.artefact(content_hash, kind)
        if row is None:
            return None
        if all((self.artefact_dir / name).is_file() for name in row["result"].get("files", {}).values()):
            return row["result"]
        return None

    def adopt(self, kind: str, content_hash: str, request: dict[str, Any]) -> dict[str, Any] | None:
        """A result whose files exist without a stored record (built by another job, e.g. a
        render's table): record and return it."""
        result = get_kind(kind).existing(request, self.artefact_dir)
        if result is not None:
            self.store.put_artefact(content_hash, kind, request, result)
        return result

    def submit(self, kind: str, request: dict[str, Any], content_hash: str) -> tuple[dict[str, Any], bool]:
        """(job row, created). Joins an active job with the same hash; QueueFull when full."""
        row, created = self.store.submit(kind, content_hash, request, self.settings.limit_queue)
        if created:
            self._start(row)
        return row, created

    def _start(self, row: dict[str, Any]) -> None:
        handle = self.executor.submit(row["kind"], row["request"], self.artefact_dir)
        with self._lock:
            self._handles[row["id"]] = handle

    def _recover(self) -> None:
        for row in self.store.active():
            if row["attempts"] + 1 >= MAX_ATTEMPTS:
                self.store.finish(row["id"], "failed", row["elapsed"],
                                  error=f"gave up after {MAX_ATTEMPTS} starts: the server stopped during "
                                        "each of them", error_type="Interrupted")
                continue
            log.info("re-queueing job %s (%s), left %s by the previous server", row["id"], row["kind"], row["state"])
            self.store.requeue(row["id"])
            self._start(row)

    # -- reading and cancelling ------------------------------------------------------------
    def job(self, job_id: str) -> dict[str, Any] | None:
        """The job's row with live progress from its handle while it runs."""
        row = self.store.job(job_id)
        if row is None:
            return None
        with self._lock:
            handle = self._handles.get(job_id)
        if handle is not None and row["state"] in ("queued", "running"):
            fraction, elapsed, eta = handle.progress()
            live = handle.state
            if live == "running":
                row.update(state="running", progress=fraction, elapsed=elapsed, eta=eta)
            row["cancel_requested"] = handle.cancel_requested()
        return row

    def cancel(self, job_id: str) -> bool:
        """Ask an active job to stop; False when it has no live handle (finished)."""
        with self._lock:
            handle = self._handles.get(job_id)
        return handle is not None and handle.cancel()

    # -- the monitor ---------------------------------------------------------------------------
    def _watch(self) -> None:
        while not self._stop.wait(self.settings.progress_interval_s):
            try:
                self._record()
            except Exception:   # noqa: BLE001 -- keep monitoring; the log says what broke
                log.exception("job monitor")

    def _record(self) -> None:
        with self._lock:
            handles = list(self._handles.items())
        for job_id, handle in handles:
            if self._stop.is_set():
                return
            state = handle.state
            fraction, elapsed, eta = handle.progress()
            if state == "running":
                self.store.started(job_id)
                self.store.progress(job_id, fraction, elapsed, eta)
                continue
            if state == "queued":
                continue
            self._finish(job_id, handle, elapsed)
            with self._lock:
                self._handles.pop(job_id, None)

    def _finish(self, job_id: str, handle: JobHandle, elapsed: float) -> None:
        self.store.started(job_id)
        if handle.state == "done":
            result = handle.result()
            self.store.put_artefact(result["hash"], handle.kind, handle.request, result)
            self.store.finish(job_id, "done", elapsed, result=result)
            return
        error = handle.error()
        self.store.finish(job_id, handle.state, elapsed, error=str(error),
                          error_type=getattr(error, "error_type", type(error).__name__))

    def close(self) -> None:
        """Stop monitoring first (a shutdown's interruptions are not outcomes), then the
        executor; unfinished jobs stay queued or running in the store for the next start."""
        self._stop.set()
        self._monitor.join()
        self.executor.shutdown()
        self.store.close()
