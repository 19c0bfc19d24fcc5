"""Measured files uploaded over HTTP (``POST /v1/measured``), stored by content hash.

The bytes are written to a temporary in the artefact folder, read by the real reader
(`bsdflab.Measured` for RGL ``.bsdf``, `bsdflab.Merl` for MERL) in a check worker process
(bsdflab.service.offload: the reader holds the GIL for seconds, never the web process's),
and only then renamed to
``<sha256>.bsdf`` / ``<sha256>.binary`` (bsdflab.util.files): a file that does not read never
enters the store, and a reader's complaint reaches the client without the temporary's path.
The same bytes give the same hash and one file; each client that uploaded them owns them
(``GET /v1/measured`` lists a client's own). A model names one as ``{"type": "measured",
"hash": h}`` or ``{"type": "merl", "hash": h}`` (bsdflab.service.artefact_refs).
"""
from __future__ import annotations

import asyncio
import contextlib
import hashlib
import os
import secrets
import shutil
import threading
from collections import defaultdict
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from fastapi import HTTPException
from starlette.concurrency import run_in_threadpool

from bsdflab.measured import Measured, Merl
from bsdflab.service.upload_gate import quota_message
from bsdflab.util.files import write_atomically

KIND = "measured"
T = TypeVar("T")
# format -> (model type, reader, file suffix)
FORMATS = {"rgl": ("measured", Measured, ".bsdf"), "merl": ("merl", Merl, ".binary")}
MODEL_FORMAT = {model_type: fmt for fmt, (model_type, _, _) in FORMATS.items()}
DESCRIPTION_PREVIEW = 200   # characters of an RGL header's description kept (a 60 MiB one was echoed whole)
# One client's uploads checked against its quota and stored one at a time: two at once
# both passed the check before either was stored (the quota overshot by an upload).
_CLIENT_LOCKS: defaultdict[str, threading.Lock] = defaultdict(threading.Lock)
_LOCKS_LOCK = threading.Lock()
FOLDER_PREFIX = ".upload-"   # an upload's private folder in the artefact folder, while it is checked
# the same folders as named by earlier versions (fit data; both kinds as ".<kind>-")
LEFT_PREFIXES = (FOLDER_PREFIX, ".fitupload-", ".measured-", ".fitdata-")


def summary(model) -> dict[str, Any]:
    """What a client needs to know about a read file (no path)."""
    if isinstance(model, Merl):
        return {"channels": ["R", "G", "B"], "spectral": False, "dims": [90, 90, 180]}
    d = model.data
    return {"channels": (["R", "G", "B"] if not d.spectral else [f"{w:g} nm" for w in d.wavelengths.tolist()]),
            "spectral": d.spectral, "n_theta_i": int(d.theta_i.size), "n_phi_i": int(d.phi_i.size),
            "resolution": int(d.values.shape[-1]), "description": _preview(d.description),
            "description_chars": len(d.description)}


def _preview(text: str) -> str:
    return text if len(text) <= DESCRIPTION_PREVIEW else text[:DESCRIPTION_PREVIEW] + "\u2026"


async def upload(jobs, data: bytes, fmt: str, client: str, quota: int | None = None) -> dict[str, Any]:
    """Check and store ``data`` as a ``fmt`` file; its record ``{"hash", "format", "summary"}``.
    ValueError with the reader's message (the file called "the upload") when it does not read;
    413 when a file new to ``client`` would take its stored bytes past ``quota``. Awaited on
    the event loop: the file I/O runs on a route thread, the check in a check worker, and
    the wait for the client's lock and for the check holds no thread."""
    async with client_turn(client):
        return await stored_after_check(jobs, data, client, quota, UploadKind(
            KIND, FORMATS[fmt][2], {"format": fmt}, f"upload{FORMATS[fmt][2]}",
            check=lambda path, folder: ("measured", {"path": path, "fmt": fmt}, "the upload"),
            record=lambda summary: {"format": fmt, "summary": {"bytes": len(data), **summary}},
            reusable=lambda row: row["result"]["format"] == fmt))


@contextlib.asynccontextmanager
async def client_turn(client: str) -> AsyncIterator[None]:
    """``client_lock(client)`` held, waited for on the event loop (polled every 20 ms: a
    thread blocked on the lock was one of the 40 every sync route shares)."""
    lock = client_lock(client)
    while not lock.acquire(blocking=False):
        await asyncio.sleep(0.02)
    try:
        yield
    finally:
        lock.release()


@dataclass(frozen=True)
class UploadKind:
    """How one kind of upload is stored: the store's ``kind``, the stored file's ``suffix``,
    the upload's ``meta``, the ``name`` of its temporary file, ``check(path, folder)`` ->
    (check, args, what) for the check worker, ``record(summary)`` -> its "format" and
    "summary", and ``reusable(row)``: whether a stored file of the same bytes answers."""
    kind: str
    suffix: str
    meta: dict[str, Any]
    name: str
    check: Callable[[str, str], tuple[str, dict[str, Any], str]]
    record: Callable[[dict[str, Any]], dict[str, Any]]
    reusable: Callable[[dict[str, Any]], bool]


async def stored_after_check(jobs, data: bytes, client: str, quota: int | None, up: UploadKind) -> dict[str, Any]:
    """The upload path of every kind, with ``client_turn`` held: the quota (413), a stored
    file of the same bytes reused when ``up.reusable(row)``, else ``data`` written in a
    private temporary folder of the artefact folder, checked in a check worker (a summary,
    or the reader's ValueError), and only then moved into the store as
    ``<sha256><suffix>``: a file that does not read never enters it. Bytes stored as
    another kind are a ValueError only once they read as this one (another key's upload of
    them is not told before)."""
    kind, meta, name = up.kind, up.meta, up.name
    # named here and made on the thread: a cancelled request knows what to remove
    folder = jobs.artefact_dir / f"{FOLDER_PREFIX}{kind}-{secrets.token_hex(8)}"
    path = folder / name

    def before() -> tuple[str, dict[str, Any] | None]:
        h = hashlib.sha256(data).hexdigest()   # not on the event loop: 50 ms for 64 MiB
        if quota is not None and not jobs.store.uploaded(h, client):
            stored = jobs.store.upload_bytes(client)
            if stored + len(data) > quota:
                raise HTTPException(413, quota_message(client, stored, len(data), quota))
        found = jobs.store.artefact(h, kind)
        if found is not None and up.reusable(found) and (jobs.artefact_dir / f"{h}{up.suffix}").is_file():
            jobs.store.put_upload(h, kind, client, meta, found["result"])
            return h, found["result"]
        folder.mkdir(mode=0o700)
        path.write_bytes(data)
        return h, None

    try:
        h, found = await _to_the_end(before)
        if found is not None:
            return found
        check_name, args, what = up.check(str(path), str(folder))
        summary = await jobs.checker.run_async(check_name, args, what, client)
        target = jobs.artefact_dir / f"{h}{up.suffix}"

        def store() -> dict[str, Any]:
            # Bytes stored as another kind that read as this one too: compared only now, so
            # that another tenant's upload of them is not told before its reading
            if jobs.store.artefact(h) is None or jobs.store.artefact(h, kind) is not None:
                # moved, not copied (the same file system): a 64 MiB upload wrote 64 MiB more
                write_atomically(target, lambda tmp: os.replace(path, tmp), suffix=target.suffix)
                result = {"hash": h, **up.record(summary), "files": {"file": target.name}}
                jobs.store.put_upload(h, kind, client, meta, result)
            row = jobs.store.artefact(h, kind)   # None: stored as another kind (just now, by another key)
            if row is None:
                raise ValueError(f"{what}: these bytes are stored as another kind of upload")
            return row["result"]

        return await _to_the_end(store)
    finally:   # after the threads (_to_the_end), before the key's turn passes on
        shutil.rmtree(folder, ignore_errors=True)


async def _to_the_end(fn: Callable[[], T]) -> T:
    """``fn()`` on a route thread, awaited until it returns even when the request is
    cancelled meanwhile (the cancel is raised then). A cancelled ``run_in_threadpool``
    returned at once while its thread went on: the folder was removed under the write, and
    the key's turn handed on before the file was counted against its quota."""
    future = asyncio.ensure_future(run_in_threadpool(fn))
    try:
        return await asyncio.shield(future)
    except asyncio.CancelledError:
        while not future.done():
            with contextlib.suppress(asyncio.CancelledError):
                await asyncio.wait({future})
        if not future.cancelled():
            future.exception()   # its outcome is no one's now: not "never retrieved"
        raise


def remove_left_folders(artefact_dir: Path) -> int:
    """Remove the private folders that an earlier server's uploads left (it was killed during
    their check: the file is inside, up to BSDFLAB_LIMIT_MEASURED_BYTES, and counted by no
    quota); how many. At start, before any upload: one server uses a data folder."""
    removed = 0
    for entry in os.scandir(artefact_dir):
        if entry.name.startswith(LEFT_PREFIXES) and entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
            removed += 1
    return removed


def client_lock(client: str) -> threading.Lock:
    """The lock that orders ``client``'s uploads of every kind (measured and fit data)."""
    with _LOCKS_LOCK:
        return _CLIENT_LOCKS[client]   # one per configured key (and the anonymous client)


def read_summary(path: str, fmt: str) -> dict[str, Any]:
    """The summary of the ``fmt`` file at ``path`` read by its reader (in a check worker,
    bsdflab.service.worker_checks); ValueError with the reader's message, the file called
    "the upload"."""
    try:
        return summary(FORMATS[fmt][1](path))
    except (ValueError, TypeError, OverflowError) as e:
        raise ValueError(f"format={fmt}: " + str(e).replace(path, "the upload")) from None


def stored_file(jobs, model_type: str, content_hash: str) -> Path | None:
    """The uploaded file of ``model_type`` ("measured" or "merl") with this hash, or None."""
    row = jobs.store.artefact(content_hash, KIND)
    if row is None or row["result"]["format"] != MODEL_FORMAT.get(model_type):
        return None
    path = jobs.artefact_dir / row["result"]["files"]["file"]
    return path if path.is_file() else None
