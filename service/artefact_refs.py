"""No server paths over HTTP: tables are named by their content hash, resolved inside the
artefact store.

The Python API and the CLI accept ``{"type": "table", "path": ...}``; over HTTP a request
names a table as ``{"type": "table", "hash": "<64 hex digits>"}`` (``GET /v1/tables``), and
this module turns that into the store's own file before any model is built. Every other
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
           '{"type": "table", "hash": "<64 hex digits>"} (GET /v1/tables lists them)')
TABLE_FIELDS = frozenset({"type", "hash", "film_lookup"})
_HASH = re.compile(r"[0-9a-f]{64}")


def refuse() -> None:
    raise HTTPException(422, REFUSED)


def resolve(value: Any, table_file) -> Any:
    """``value`` (a request's JSON) with every ``{"type": "table", "hash": h}`` replaced by
    the store's table file ``table_file(h)`` (a Path, or None when the store has no such
    table); any other path-bearing field is refused (422, one message)."""
    check.nesting("the request", value)   # without recursion: the walk below recurses
    return _resolve(value, table_file)


def _resolve(value: Any, table_file) -> Any:
    if isinstance(value, list):
        return [_resolve(v, table_file) for v in value]
    if not isinstance(value, dict):
        return value
    if value.get("type") == "table":
        return _table(value, table_file)
    out = {}
    for k, v in value.items():
        if k in PATH_FIELDS and v is not None and not isinstance(v, (bool, int, float)):
            refuse()
        out[k] = _resolve(v, table_file)
    return out


def _table(value: dict[str, Any], table_file) -> dict[str, Any]:
    if set(value) - TABLE_FIELDS:
        refuse()
    h = value.get("hash")
    if not isinstance(h, str) or _HASH.fullmatch(h) is None:
        raise HTTPException(422, 'a table is named by its content hash: {"type": "table", "hash": '
                                 '"<64 lower-case hex digits>"}')
    path = table_file(h)
    if path is None:
        raise HTTPException(422, f"no table {h} in this server's store (GET /v1/tables)")
    return {**{k: v for k, v in value.items() if k != "hash"}, "path": str(path)}


def public(value: Any, artefact_dir: Path) -> Any:
    """The inverse for answers: a table model that points into the store is shown by its
    hash, so no server path ever leaves in a response."""
    if isinstance(value, list):
        return [public(v, artefact_dir) for v in value]
    if not isinstance(value, dict):
        return value
    if value.get("type") == "table" and isinstance(value.get("path"), str):
        return {**{k: v for k, v in value.items() if k != "path"}, "hash": Path(value["path"]).stem}
    return {k: public(v, artefact_dir) for k, v in value.items()}
