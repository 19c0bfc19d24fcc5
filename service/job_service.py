"""The service's job manager: the SQLite store, the artefact folder and an executor.

A request is normalised by its kind (bsdflab.jobs), hashed, and then either answered from
the artefact folder (already computed), joined to the active job with the same hash
(dedup), or stored as a new queued job and submitted. A monitor thread copies progress
and outcomes from the executor's handles into the store. On start, jobs a previous
server left queued or running are re-queued (their artefacts are written atomically, so
nothing half-written is ever found). Stopping leaves unfinished jobs in the store for the
next start without counting a start against them; a job found *running* at start (its
server died under it) counts one, and the third such start fails it.
"""
from __future__ import annotations

import logging
import threading
from pathlib import Path
from typing import Any

from bsdflab.jobs import JobHandle, get_kind, make_executor
from bsdflab.jobs import tabulate as tabulate_kind
from bsdflab.measured import store as measured_store
from bsdflab.service import uploads
from bsdflab.service.auth import ANONYMOUS, Client
from bsdflab.service.errors import cut_message
from bsdflab.service.offload import Checker
from bsdflab.service.settings import Settings
from bsdflab.service.store import JobStore
from bsdflab.tables import cache as table_cache
from bsdflab.util.settings import hand_down

log = logging.getLogger("bsdflab.service")
TABULATE = "tabulate"
MAX_ATTEMPTS = 3   # a job that a restart finds unfinished this often has killed its server


class JobService:
    def __init__(self, settings: Settings):
        self.settings = settings
        self.artefact_dir: Path = settings.artefact_dir
        self.artefact_dir.mkdir(parents=True, exist_ok=True)
        if left := uploads.remove_left_folders(self.artefact_dir):
            log.warning("removed %d upload folders the last server left (stopped during their check)", left)
        self.store = JobStore(settings.db_path)
        measured_store.add_folder(self.artefact_dir)   # uploads by hash, here and in the workers started next
        # One table cache for the CLI, table jobs and render jobs (BSDFLAB_CACHE_DIR, default
        # the CLI's): the workers started next and the renders' tables find it by the variable.
        self.table_dir: Path = table_cache.cache_dir(settings.cache_dir)
        self.table_dir.mkdir(parents=True, exist_ok=True)
        hand_down("cache_dir", self.table_dir)
        self.executor = make_executor(settings.executor, settings.workers)
        # client files (uploads, a render's stored materials) are read in their own worker
        # processes, whatever the executor: never in the web process, never behind a render
        self.checker = Checker(settings, self.artefact_dir, {self.table_dir: "<table store>",
                                                             settings.data_dir: "<data folder>"})
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
        folder = self.folder(kind)
        if all((folder / name).is_file() for name in row["result"].get("files", {}).values()):
            return row["result"]
        return None

    def folder(self, kind: str) -> Path:
        """Where a kind's files live: tables in the table cache, the rest in the artefacts."""
        return self.table_dir if kind == TABULATE else self.artefact_dir

    def table(self, content_hash: str) -> dict[str, Any] | None:
        """A table's result by its hash: the stored record, or a table file in the store that
        another job made (a render's, the CLI's), described from its header; None otherwise."""
        result = self.cached(TABULATE, content_hash)
        if result is not None:
            return result
        path = self.table_dir / f"{content_hash}.exr"
        if path.is_file():
            try:
                return {"hash": content_hash, "files": {"exr": path.name}, **tabulate_kind.describe(path)}
            except ValueError:   # not a table (a render's image has the same naming)
                return None
        return None

    def table_file(self, content_hash: str) -> Path | None:
        """The store's file of the table ``content_hash`` (how HTTP requests name tables)."""
        result = self.table(content_hash)
        return None if result is None else self.table_dir / result["files"]["exr"]

    def stored_file(self, model_type: str, content_hash: str) -> Path | None:
        """The store's file of a model named by hash over HTTP: a table, or an uploaded
        measured file of the matching format (bsdflab.service.uploads)."""
        if model_type == "table":
            return self.table_file(content_hash)
        return uploads.stored_file(self, model_type, content_hash)

    def adopt(self, kind: str, content_hash: str, request: dict[str, Any]) -> dict[str, Any] | None:
        """A result whose files exist without a stored record (built by another job, e.g. a
        render's table): record and return it."""
        result = get_kind(kind).existing(request, self.folder(kind))
        if result is not None:
            self.store.put_artefact(content_hash, kind, request, result)
        return result

    def submit(self, kind: str, request: dict[str, Any], content_hash: str, client: Client = ANONYMOUS
               ) -> tuple[dict[str, Any], bool]:
        """(job row, created). Joins an active job with the same hash; QueueFull when the
        queue, or the client's share of it, is full."""
        row, created = self.store.submit(kind, content_hash, request, self.settings.limit_queue,
                                         owner=client.name, owner_limit=client.max_jobs,
                                         reserve=self._reserve(client))
        if created:
            log.info("job %s (%s) queued for client %s", row["id"], kind, client.name)
            self._start(row)
        return row, created

    def room(self, kind: str, content_hash: str, client: Client = ANONYMOUS) -> None:
        """QueueFull when ``submit`` would refuse this job of ``client`` now."""
        self.store.room(kind, content_hash, self.settings.limit_queue, owner=client.name,
                        owner_limit=client.max_jobs, reserve=self._reserve(client))

    def _reserve(self, client: Client) -> int:
        """Slots a tenant key with jobs leaves free for other keys; an admin key (and the
        open service's anonymous client) is the operator and may use them."""
        return 0 if client.admin else min(self.settings.limit_queue_reserve, self.settings.limit_queue - 1)

    def visible(self, row: dict[str, Any] | None, client: Client) -> dict[str, Any] | None:
        """The row when ``client`` may see it (an admin, or a client that created or joined
        the job), else None: another client's job looks like no job at all."""
        if row is None or client.admin or self.store.sees(row["id"], client.name):
            return row
        return None

    def job_hint(self, kind: str, content_hash: str, client: Client) -> str:
        """"; job <id> is <state>" for a 404 when ``client`` may see the latest job of this
        hash, else "" (another tenant's job is never named)."""
        job = self.visible(self.store.latest_for(kind, content_hash), client)
        return "" if job is None else f"; job {job['id']} is {job['state']}"

    def _start(self, row: dict[str, Any]) -> None:
        handle = self.executor.submit(row["kind"], row["request"], self.folder(row["kind"]))
        with self._lock:
            self._handles[row["id"]] = handle

    def _recover(self) -> None:
        """Start what the last server left. Only a job the store shows running counts a
        start (that server died while it ran: it may be what killed it); a graceful stop
        released its running jobs to queued (``close``), and a queued job never ran."""
        for row in self.store.active():
            crashed = row["state"] == "running"
            if crashed and row["attempts"] + 1 >= MAX_ATTEMPTS:
                self.store.finish(row["id"], "failed", row["elapsed"],
                                  error=f"gave up after {MAX_ATTEMPTS} starts: the server stopped during "
                                        "each of them", error_type="Interrupted")
                log.warning("job %s (%s) failed after restart: given up after %d starts", row["id"], row["kind"],
                            MAX_ATTEMPTS)
                continue
            log.info("job %s (%s) re-queued after restart (the previous server left it %s)",
                     row["id"], row["kind"], row["state"])
            self.store.requeue(row["id"], count=crashed)
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
                if self.store.started(job_id):
                    log.info("job %s (%s) started", job_id, handle.kind)
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
            log.info("job %s (%s) done in %.1f s", job_id, handle.kind, elapsed)
            return
        error = handle.error()
        # as every client error: cut short, and no server folder (a worker's OSError names its file)
        public_error = cut_message(str(error).replace(str(self.settings.data_dir), "<data folder>"))
        self.store.finish(job_id, handle.state, elapsed, error=public_error,
                          error_type=getattr(error, "error_type", type(error).__name__))
        log.info("job %s (%s) %s after %.1f s: %s", job_id, handle.kind, handle.state, elapsed, error)

    def close(self) -> None:
        """Stop monitoring first (a shutdown's interruptions are not outcomes), then the
        executor; unfinished jobs go back to queued in the store for the next start, no
        start counted against them (a graceful stop is not the job's fault), except those a
        client asked to cancel, recorded cancelled (else re-run at every start, for ever)."""
        self._stop.set()
        self._monitor.join()
        with self._lock:   # before the executor's shutdown, which asks every job to stop
            asked = [(job_id, h.progress()[1]) for job_id, h in self._handles.items() if h.cancel_requested()]
        for job_id, elapsed in asked:   # a client's cancel outlives the stop: never re-queued
            self.store.finish(job_id, "cancelled", elapsed, error="cancelled (the server stopped before the job "
                              "reached a point where it stops)", error_type="JobCancelled")
        self.checker.close()
        self.executor.shutdown()
        released = self.store.release_running()
        if released:
            log.info("%d running jobs re-queued for the next start (graceful stop)", released)
        self.store.close()
