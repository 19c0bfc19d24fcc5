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

import hashlib
import threading
from collections import defaultdict
from pathlib import Path
from typing import Any

from fastapi import HTTPException

from bsdflab.measured import Measured, Merl
from bsdflab.service.upload_gate import quota_message
from bsdflab.util.files import write_atomically

KIND = "measured"
# format -> (model type, reader, file suffix)
FORMATS = {"rgl": ("measured", Measured, ".bsdf"), "merl": ("merl", Merl, ".binary")}
MODEL_FORMAT = {model_type: fmt for fmt, (model_type, _, _) in FORMATS.items()}
DESCRIPTION_PREVIEW = 200   # characters of an RGL header's description kept (a 60 MiB one was echoed whole)
# One client's uploads checked against its quota and stored one at a time: two at once
# both passed the check before either was stored (the quota overshot by an upload).
_CLIENT_LOCKS: defaultdict[str, threading.Lock] = defaultdict(threading.Lock)
_LOCKS_LOCK = threading.Lock()


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


def upload(jobs, data: bytes, fmt: str, client: str, quota: int | None = None) -> dict[str, Any]:
    """Check and store ``data`` as a ``fmt`` file; its record ``{"hash", "format", "summary"}``.
    ValueError with the reader's message (the file called "the upload") when it does not read;
    413 when a file new to ``client`` would take its stored bytes past ``quota``."""
    with client_lock(client):
        return _upload(jobs, data, fmt, client, quota)


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


def check_file(jobs, path: str, fmt: str, client: str | None = None) -> dict[str, Any]:
    """``read_summary`` in a check worker process (bsdflab.service.offload)."""
    return jobs.checker.run("measured", {"path": path, "fmt": fmt}, "the upload", client)


def _upload(jobs, data: bytes, fmt: str, client: str, quota: int | None) -> dict[str, Any]:
    suffix = FORMATS[fmt][2]
    h = hashlib.sha256(data).hexdigest()
    if quota is not None and not jobs.store.uploaded(h, client):
        stored = jobs.store.upload_bytes(client)
        if stored + len(data) > quota:
            raise HTTPException(413, quota_message(client, stored, len(data), quota))
    found = jobs.store.artefact(h, KIND)
    target = jobs.artefact_dir / f"{h}{suffix}"
    if found is not None and found["result"]["format"] == fmt and target.is_file():
        jobs.store.put_upload(h, KIND, client, {"format": fmt}, found["result"])
        return found["result"]
    read = {}

    def write(tmp: str) -> None:
        Path(tmp).write_bytes(data)
        read.update(check_file(jobs, tmp, fmt, client))

    write_atomically(target, write, suffix=suffix)
    result = {"hash": h, "format": fmt, "summary": {"bytes": len(data), **read},
              "files": {"file": target.name}}
    jobs.store.put_upload(h, KIND, client, {"format": fmt}, result)
    return jobs.store.artefact(h, KIND)["result"]


def stored_file(jobs, model_type: str, content_hash: str) -> Path | None:
    """The uploaded file of ``model_type`` ("measured" or "merl") with this hash, or None."""
    row = jobs.store.artefact(content_hash, KIND)
    if row is None or row["result"]["format"] != MODEL_FORMAT.get(model_type):
        return None
    path = jobs.artefact_dir / row["result"]["files"]["file"]
    return path if path.is_file() else None
