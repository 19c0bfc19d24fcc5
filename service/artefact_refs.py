"""No server paths over HTTP: tables and measured files are named by their content hash,
resolved inside the artefact store.

The Python API and the CLI accept ``{"type": "table", "path": ...}`` (and ``measured``,
``merl``); over HTTP a request names one as ``{"type": "table", "hash": "<64 hex digits>"}``
(``GET /v1/tables``), ``{"type": "measured", "hash": ...}`` or ``{"type": "merl", "hash": ...}``
(uploaded with ``POST /v1/measured``, listed by ``GET /v1/measured``), and this module turns
that into the store's own file before any model is built. Every other
path-bearing field (a table's ``path`` or ``table``, a scene file, a mesh, an environment
map, a texture) is refused with one message, the same whatever the path names, and before
anything touches the file system: a client learns nothing about the server's files.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from fastapi import HTTPException

from bsdflab.util import args as check

# Keys that carry a file name anywhere in the Python API's dicts (models, scene options).
PATH_FIELDS = frozenset({"path", "table", "file", "filename", "scene_file", "mesh", "mesh_file",
                         "environment_map", "envmap", "env_map", "texture", "image", "directory", "folder",
                         "dir", "url", "uri", "measured_file", "data_file"})
REFUSED = ("server paths are not accepted over HTTP: name a table by its content hash, "
           '{"type": "table", "hash": "<64 hex digits>"} (GET /v1/tables lists them), and a measured '
           'file as {"type": "measured" or "merl", "hash": ...} (POST /v1/measured uploads one)')
# The model types that name a store file, the keys they may carry and where a client lists them.
STORED = {"table": (frozenset({"type", "hash", "film_lookup"}), "GET /v1/tables"),
          "measured": (frozenset({"type", "hash"}), "GET /v1/measured"),
          "merl": (frozenset({"type", "hash"}), "GET /v1/measured")}
_HASH = re.compile(r"[0-9a-f]{64}")


def refuse() -> None:
    raise HTTPException(422, REFUSED)


def resolve(value: Any, stored_file) -> Any:
    """``value`` (a request's JSON) with every ``{"type": t, "hash": h}`` of a type in
    ``STORED`` replaced by the store's file ``stored_file(t, h)`` (a Path, or None when the
    store has no such file); any other path-bearing field is refused (422, one message)."""
    check.nesting("the request", value)   # without recursion: the walk below recurses
    return _resolve(value, stored_file)


def _resolve(value: Any, stored_file) -> Any:
    if isinstance(value, list):
        return [_resolve(v, stored_file) for v in value]
    if not isinstance(value, dict):
        return value
    if isinstance(value.get("type"), str) and value["type"] in STORED:
        return _stored(value, stored_file)
    out = {}
    for k, v in value.items():
        if k in PATH_FIELDS and v is not None and not isinstance(v, (bool, int, float)):
            refuse()
        out[k] = _resolve(v, stored_file)
    return out


def _stored(value: dict[str, Any], stored_file) -> dict[str, Any]:
    kind = value["type"]
    fields, listing = STORED[kind]
    if set(value) - fields:
        refuse()
    h = value.get("hash")
    if not isinstance(h, str) or _HASH.fullmatch(h) is None:
        raise HTTPException(422, f'a {kind} is named by its content hash: {{"type": "{kind}", "hash": '
                                 '"<64 lower-case hex digits>"}')
    path = stored_file(kind, h)
    if path is None:
        raise HTTPException(422, f"no {kind} {h} in this server's store ({listing})")
    return {**{k: v for k, v in value.items() if k != "hash"}, "path": str(path)}


def public(value: Any, artefact_dir: Path | None = None) -> Any:
    """The inverse for answers: a table or measured model that points into the store is
    shown by its hash, so no server path ever leaves in a response."""
    if isinstance(value, list):
        return [public(v, artefact_dir) for v in value]
    if not isinstance(value, dict):
        return value
    if isinstance(value.get("type"), str) and value["type"] in STORED and isinstance(value.get("path"), str):
        return {**{k: v for k, v in value.items() if k != "path"}, "hash": Path(value["path"]).stem}
    return {k: public(v, artefact_dir) for k, v in value.items()}
