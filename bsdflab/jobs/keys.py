"""A job's key: the SHA-256 of its kind, the package version and its canonical request, so
the same request of the same release is one job (render and fit jobs share this rule)."""
from __future__ import annotations

import hashlib
from typing import Any

from bsdflab._version import __version__
from bsdflab.tables.file_format import canonical_json


def plain_json(request: dict[str, Any], kind: str) -> str:
    """The canonical JSON text of ``request``; ValueError naming the kind when it is not
    plain JSON (a set, a NaN, a non-string key)."""
    try:
        return canonical_json(request)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{kind} request is not plain JSON: {e}") from None


def job_key(kind: str, request: dict[str, Any]) -> str:
    text = plain_json({"kind": kind, "bsdflab_version": __version__, "request": request}, kind)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()
