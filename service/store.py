"""The embedded job store: one SQLite file in WAL mode, its schema versioned.

Two tables. ``jobs``: every job with its kind, content hash, state, progress and outcome.
``artefacts``: finished results by content hash (the files themselves live in the
content-addressed artefact folder). WAL with synchronous=NORMAL survives the server being
killed (only an OS crash can lose the last commits); a fresh file gets the schema on start.
"""
from __future__ import annotations

import json
import sqlite3
import threading
import time
import uuid
from pathlib import Path
from typing import Any

SCHEMA_VERSION = 3
ACTIVE = ("queued", "running")
SCHEMA = """
CREATE TABLE jobs (
    id TEXT PRIMARY KEY,
    kind TEXT NOT NULL,
    hash TEXT NOT NULL,
    state TEXT NOT NULL,
    request TEXT NOT NULL,
    result TEXT,
    error TEXT,
    error_type TEXT,
    progress REAL NOT NULL DEFAULT 0,
    elapsed REAL NOT NULL DEFAULT 0,
    eta REAL,
    created REAL NOT NULL,
    started REAL,
    finished REAL,
    attempts INTEGER NOT NULL DEFAULT 0,
    owner TEXT
);
CREATE INDEX jobs_by_hash ON jobs (kind, hash, state);
CREATE INDEX jobs_by_state ON jobs (state);
CREATE TABLE artefacts (
    hash TEXT PRIMARY KEY,
    kind TEXT NOT NULL,
    created REAL NOT NULL,
    request TEXT NOT NULL,
    result TEXT NOT NULL
);
CREATE INDEX artefacts_by_kind ON artefacts (kind, created);
""" + """
CREATE TABLE job_clients (
    job_id TEXT NOT NULL,
    client TEXT NOT NULL,
    PRIMARY KEY (job_id, client)
);
CREATE INDEX jobs_by_owner ON jobs (owner, state);
""" + """
CREATE TABLE uploads (
    hash TEXT NOT NULL,
    client TEXT NOT NULL,
    PRIMARY KEY (hash, client)
);
"""
# Version 1 -> 2: jobs belong to clients (the creator owns, clients that joined see).
MIGRATE_1_2 = """
ALTER TABLE jobs ADD COLUMN owner TEXT;
CREATE TABLE job_clients (job_id TEXT NOT NULL, client TEXT NOT NULL, PRIMARY KEY (job_id, client));
CREATE INDEX jobs_by_owner ON jobs (owner, state);
"""
# Version 2 -> 3: uploaded artefacts (measured files) belong to the clients that uploaded them.
MIGRATE_2_3 = "CREATE TABLE uploads (hash TEXT NOT NULL, client TEXT NOT NULL, PRIMARY KEY (hash, client));"


class QueueFull(Exception):
    """More active jobs than the queue limit (or the client's share) allows."""

    def __init__(self, message: str, setting: str = "limit_queue"):
        super().__init__(message)
        self.setting = setting


class StoreError(Exception):
    """The store file cannot be used (made by a newer version, or not a job store)."""


def _row(cursor: sqlite3.Cursor, values: tuple) -> dict[str, Any]:
    row = {d[0]: v for d, v in zip(cursor.description, values)}
    for name in ("request", "result"):
        if row.get(name) is not None:
            row[name] = json.loads(row[name])
    return row


class JobStore:
    """Thread-safe access to the store (one connection, serialised by a lock)."""

    def __init__(self, path: Path):
        path.parent.mkdir(parents=True, exist_ok=True)
        self._lock = threading.Lock()
        self._db = sqlite3.connect(str(path), check_same_thread=False, isolation_level=None, timeout=30)
        self._db.row_factory = _row
        with self._lock:
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute("PRAGMA synchronous=NORMAL")
            self._migrate(path)

    def _migrate(self, path: Path) -> None:
        version = self._db.execute("PRAGMA user_version").fetchone()["user_version"]
        if version > SCHEMA_VERSION:
            raise StoreError(f"{path} has schema version {version}; this bsdflab reads up to "
                             f"{SCHEMA_VERSION} (use a newer bsdflab or another --data-dir)")
        if version == 0:
            tables = self._db.execute("SELECT count(*) AS n FROM sqlite_master").fetchone()["n"]
            if tables:
                raise StoreError(f"{path} is an SQLite file but not a bsdflab job store")
            self._db.executescript("BEGIN;" + SCHEMA + f"PRAGMA user_version={SCHEMA_VERSION}; COMMIT;")
            return
        if version == 1:
            self._db.executescript("BEGIN;" + MIGRATE_1_2 + "PRAGMA user_version=2; COMMIT;")
        if version <= 2:
            self._db.executescript("BEGIN;" + MIGRATE_2_3 + "PRAGMA user_version=3; COMMIT;")

    def close(self) -> None:
        with self._lock:
            self._db.close()

    # -- jobs ------------------------------------------------------------------------------
    def room(self, kind: str, content_hash: str, queue_limit: int, owner: str | None = None,
             owner_limit: int | None = None, reserve: int = 0) -> None:
        """QueueFull when ``submit`` would refuse this job now (a job it would join is never
        refused): asked before a job's submission costs a check worker's time."""
        with self._lock:
            found = self._db.execute("SELECT 1 FROM jobs WHERE kind = ? AND hash = ? AND state IN ('queued', "
                                     "'running') LIMIT 1", (kind, content_hash)).fetchone()
            if found is None:
                self._check_room(queue_limit, owner, owner_limit, reserve)

    def _check_room(self, queue_limit: int, owner: str | None, owner_limit: int | None, reserve: int) -> None:
        active = self._db.execute(
            "SELECT count(*) AS n FROM jobs WHERE state IN ('queued', 'running')").fetchone()["n"]
        if active >= queue_limit:
            raise QueueFull(f"{active} jobs are queued or running, the limit", "limit_queue")
        mine = self._db.execute("SELECT count(*) AS n FROM jobs WHERE owner IS ? AND state IN "
                                "('queued', 'running')", (owner,)).fetchone()["n"]
        if owner_limit is not None and mine >= owner_limit:
            raise QueueFull(f"client {owner!r} has {mine} jobs queued or running, its share",
                            "limit_queue_per_key")
        if mine and queue_limit - active - 1 < reserve:   # a key with no job may take the reserve
            raise QueueFull(f"client {owner!r} has {mine} jobs queued or running and the last {reserve} "
                            "slots are kept for other keys", "limit_queue_reserve")

    def submit(self, kind: str, content_hash: str, request: dict[str, Any], queue_limit: int,
               owner: str | None = None, owner_limit: int | None = None, reserve: int = 0
               ) -> tuple[dict[str, Any], bool]:
        """(job, created): the active job with this kind and hash (which ``owner`` then sees
        too), or a new queued one owned by ``owner``. Raises QueueFull when a new job would
        exceed ``queue_limit`` active jobs, or ``owner_limit`` active jobs of its owner, or when
        an owner that has active jobs would take one of the last ``reserve`` free slots (kept
        for a key that has none, so a new tenant always finds room)."""
        with self._lock:
            self._db.execute("BEGIN IMMEDIATE")
            try:
                found = self._db.execute(
                    "SELECT * FROM jobs WHERE kind = ? AND hash = ? AND state IN ('queued', 'running') "
                    "ORDER BY created LIMIT 1", (kind, content_hash)).fetchone()
                if found is not None:
                    self._db.execute("INSERT OR IGNORE INTO job_clients (job_id, client) VALUES (?, ?)",
                                     (found["id"], owner))
                    self._db.execute("COMMIT")
                    return found, False
                self._check_room(queue_limit, owner, owner_limit, reserve)
                job_id = uuid.uuid4().hex
                self._db.execute(
                    "INSERT INTO jobs (id, kind, hash, state, request, created, owner) "
                    "VALUES (?, ?, ?, 'queued', ?, ?, ?)",
                    (job_id, kind, content_hash, json.dumps(request), time.time(), owner))
                self._db.execute("INSERT INTO job_clients (job_id, client) VALUES (?, ?)", (job_id, owner))
                self._db.execute("COMMIT")
            except BaseException:
                self._db.execute("ROLLBACK")
                raise
            return self._get(job_id), True

    def _get(self, job_id: str) -> dict[str, Any] | None:
        return self._db.execute("SELECT * FROM jobs WHERE id = ?", (job_id,)).fetchone()

    def job(self, job_id: str) -> dict[str, Any] | None:
        with self._lock:
            return self._get(job_id)

    def jobs(self, limit: int = 100, state: str | None = None, client: str | None = None) -> list[dict[str, Any]]:
        """The latest jobs, of one state and/or that ``client`` sees (None: every job)."""
        where, args = [], []
        if state is not None:
            where.append("state = ?")
            args.append(state)
        if client is not None:
            where.append("id IN (SELECT job_id FROM job_clients WHERE client = ?)")
            args.append(client)
        clause = f"WHERE {' AND '.join(where)} " if where else ""
        with self._lock:
            return self._db.execute(f"SELECT * FROM jobs {clause}ORDER BY created DESC LIMIT ?",
                                    (*args, limit)).fetchall()

    def counts(self) -> list[tuple[str, str, int]]:
        """(kind, state, number of jobs) for every kind and state in the store."""
        with self._lock:
            rows = self._db.execute("SELECT kind, state, count(*) AS n FROM jobs GROUP BY kind, state").fetchall()
        return [(r["kind"], r["state"], r["n"]) for r in rows]

    def sees(self, job_id: str, client: str) -> bool:
        """Whether ``client`` created or joined job ``job_id``."""
        with self._lock:
            return self._db.execute("SELECT 1 AS yes FROM job_clients WHERE job_id = ? AND client = ?",
                                    (job_id, client)).fetchone() is not None

    def artefacts_of(self, kind: str, client: str, limit: int = 1000) -> list[dict[str, Any]]:
        """Artefacts made by jobs ``client`` sees, newest first."""
        with self._lock:
            return self._db.execute(
                "SELECT * FROM artefacts WHERE kind = ? AND hash IN (SELECT j.hash FROM jobs j JOIN job_clients c "
                "ON c.job_id = j.id WHERE c.client = ? AND j.kind = ?) ORDER BY created DESC LIMIT ?",
                (kind, client, kind, limit)).fetchall()

    def active(self) -> list[dict[str, Any]]:
        """Queued and running jobs, oldest first (what a restart re-queues)."""
        with self._lock:
            return self._db.execute("SELECT * FROM jobs WHERE state IN ('queued', 'running') "
                                    "ORDER BY created").fetchall()

    def latest_for(self, kind: str, content_hash: str) -> dict[str, Any] | None:
        with self._lock:
            return self._db.execute("SELECT * FROM jobs WHERE kind = ? AND hash = ? ORDER BY created DESC "
                                    "LIMIT 1", (kind, content_hash)).fetchone()

    def requeue(self, job_id: str, count: bool) -> None:
        """Queued again from the start; ``count``: the interrupted run counts as a start."""
        with self._lock:
            self._db.execute("UPDATE jobs SET state = 'queued', progress = 0, elapsed = 0, eta = NULL, "
                             "started = NULL, attempts = attempts + ? WHERE id = ?", (int(count), job_id))

    def release_running(self) -> int:
        """A graceful stop: every running job back to queued, no start counted (it was not
        the job's fault); the number released."""
        with self._lock:
            return self._db.execute("UPDATE jobs SET state = 'queued', progress = 0, elapsed = 0, eta = NULL, "
                                    "started = NULL WHERE state = 'running'").rowcount

    def started(self, job_id: str) -> bool:
        """Mark a queued job running; True when it was queued until now."""
        with self._lock:
            return self._db.execute("UPDATE jobs SET state = 'running', started = ? WHERE id = ? AND state = 'queued'",
                                    (time.time(), job_id)).rowcount > 0

    def progress(self, job_id: str, fraction: float, elapsed: float, eta: float | None) -> None:
        with self._lock:
            self._db.execute("UPDATE jobs SET progress = ?, elapsed = ?, eta = ? WHERE id = ? AND state = 'running'",
                             (fraction, elapsed, eta, job_id))

    def finish(self, job_id: str, state: str, elapsed: float, result: dict[str, Any] | None = None,
               error: str | None = None, error_type: str | None = None) -> None:
        with self._lock:
            self._db.execute(
                "UPDATE jobs SET state = ?, result = ?, error = ?, error_type = ?, finished = ?, elapsed = ?, "
                "eta = NULL, progress = CASE WHEN ? = 'done' THEN 1 ELSE progress END "
                "WHERE id = ? AND state IN ('queued', 'running')",
                (state, None if result is None else json.dumps(result), error, error_type, time.time(),
                 elapsed, state, job_id))

    # -- artefacts -------------------------------------------------------------------------
    def put_artefact(self, content_hash: str, kind: str, request: dict[str, Any], result: dict[str, Any]) -> None:
        with self._lock:
            self._db.execute("INSERT OR REPLACE INTO artefacts (hash, kind, created, request, result) "
                             "VALUES (?, ?, ?, ?, ?)",
                             (content_hash, kind, time.time(), json.dumps(request), json.dumps(result)))

    def put_upload(self, content_hash: str, kind: str, client: str, request: dict[str, Any],
                   result: dict[str, Any]) -> None:
        """Record an uploaded artefact (once: the same bytes keep their first record) and
        that ``client`` uploaded it."""
        with self._lock:
            self._db.execute("BEGIN IMMEDIATE")
            try:
                self._db.execute("INSERT OR IGNORE INTO artefacts (hash, kind, created, request, result) "
                                 "VALUES (?, ?, ?, ?, ?)",
                                 (content_hash, kind, time.time(), json.dumps(request), json.dumps(result)))
                self._db.execute("INSERT OR IGNORE INTO uploads (hash, client) VALUES (?, ?)", (content_hash, client))
                self._db.execute("COMMIT")
            except BaseException:
                self._db.execute("ROLLBACK")
                raise

    def uploads_of(self, kind: str, client: str | None, limit: int = 1000) -> list[dict[str, Any]]:
        """Uploaded artefacts of ``kind`` that ``client`` uploaded (None: all), newest first."""
        mine = "" if client is None else "AND hash IN (SELECT hash FROM uploads WHERE client = ?) "
        with self._lock:
            return self._db.execute(f"SELECT * FROM artefacts WHERE kind = ? {mine}ORDER BY created DESC LIMIT ?",
                                    (kind, *(() if client is None else (client,)), limit)).fetchall()

    def uploaded(self, content_hash: str, client: str) -> bool:
        with self._lock:
            return self._db.execute("SELECT 1 AS yes FROM uploads WHERE hash = ? AND client = ?",
                                    (content_hash, client)).fetchone() is not None

    def upload_bytes(self, client: str) -> int:
        """Bytes of the uploaded files ``client`` uploaded (each file counted once)."""
        with self._lock:
            row = self._db.execute(
                "SELECT coalesce(sum(json_extract(result, '$.summary.bytes')), 0) AS n FROM artefacts "
                "WHERE hash IN (SELECT hash FROM uploads WHERE client = ?)", (client,)).fetchone()
        return int(row["n"])

    def artefact(self, content_hash: str, kind: str | None = None) -> dict[str, Any] | None:
        with self._lock:
            row = self._db.execute("SELECT * FROM artefacts WHERE hash = ?", (content_hash,)).fetchone()
        return row if row is not None and (kind is None or row["kind"] == kind) else None

    def artefacts(self, kind: str, limit: int = 1000) -> list[dict[str, Any]]:
        with self._lock:
            return self._db.execute("SELECT * FROM artefacts WHERE kind = ? ORDER BY created DESC LIMIT ?",
                                    (kind, limit)).fetchall()
