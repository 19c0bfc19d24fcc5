"""Measured files named by content hash: ``{"type": "measured", "hash": h}`` (RGL) and
``{"type": "merl", "hash": h}`` read ``<h>.bsdf`` / ``<h>.binary`` from a store folder.

The HTTP service keeps uploads under their SHA-256 in its artefact folder and registers it
here (``add_folder``; also in ``BSDFLAB_MEASURED_STORE``, os.pathsep-separated, so worker
processes find it): a model, a job request and a table file's ``bsdflab.model`` attribute
then name the file by its hash, never by a path on the server (docs/measured.md).
"""
from __future__ import annotations

import os
import re
from pathlib import Path

ENV = "BSDFLAB_MEASURED_STORE"
_HASH = re.compile(r"[0-9a-f]{64}")
_folders: list[Path] = []


def add_folder(folder: str | os.PathLike) -> None:
    """Look for hashed files in ``folder`` too (this process and processes it starts)."""
    folder = Path(folder)
    if folder not in _folders:
        _folders.insert(0, folder)
    known = [p for p in os.environ.get(ENV, "").split(os.pathsep) if p]
    if str(folder) not in known:
        os.environ[ENV] = os.pathsep.join([str(folder), *known])


def folders() -> list[Path]:
    from_env = [Path(p) for p in os.environ.get(ENV, "").split(os.pathsep) if p]
    return _folders + [f for f in from_env if f not in _folders]


def locate(content_hash, suffix: str, what: str) -> str:
    """The stored file ``<content_hash><suffix>``; ValueError naming the hash (never a
    folder) when it is malformed or in no store folder."""
    if not isinstance(content_hash, str) or _HASH.fullmatch(content_hash) is None:
        raise ValueError(f"hash must be the 64 lower-case hex digits of a stored {what}")
    for folder in folders():
        path = folder / f"{content_hash}{suffix}"
        if path.is_file():
            return str(path)
    raise ValueError(f"no stored {what} {content_hash} (uploaded files are looked up in {ENV})")
