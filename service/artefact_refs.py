"""No server paths over HTTP: tables and measured files are named by their content hash,
resolved inside the artefact store.

The Python API and the CLI accept ``{"type": "table", "path": ...}`` (and ``measured``,
``merl``); over HTTP a request names one as ``{"type": "table", "hash": "<64 hex digits>"}``
(``GET /v1/tables``), ``{"type": "measured", "hash": ...}`` or ``{"type": "merl", "hash": ...}``
(uploaded with ``POST /v1/measured``, listed by ``GET /v1/measured``), accepted only where a
model goes (a request's ``model``, a layered model's ``base`` and ``interfaces``) and
checked against the store before any model is built: a table becomes the store's file, a
measured file keeps its hash (bsdflab.measured.store finds it). Every other
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


MISPLACED = ('a stored file named by hash ({"type": "table", "measured" or "merl", "hash": ...}) is accepted '
             'only where a model goes: a request\'s "model" (a render\'s "options.material"), a layered '
             'model\'s "base" or "interfaces", or a tabulated material\'s "model"')
MODEL_SLOTS = (("model",),)                            # where a request holds a model (key paths)
RENDER_SLOTS = (("options", "material"),)              # a render's material (bsdflab.scenes.material_spec)
NESTED_MODELS = {"layered": ("base", "interfaces"),    # a model's keys that hold models
                 "tabulated": ("model",)}


def refuse() -> None:
    raise HTTPException(422, REFUSED)


def resolve(value: Any, stored_file, max_refs: int | None = None, slots=MODEL_SLOTS) -> Any:
    """``value`` (a request's JSON) with every ``{"type": t, "hash": h}`` where a model goes
    checked against the store (``stored_file(t, h)``: a Path, or None when the store has no
    such file): a table becomes the store's file, a measured file keeps its hash (its model
    finds it in the store folder, bsdflab.measured.store, so no path enters the request, an
    error or a table file). A reference anywhere else is refused without being looked up,
    as is any path-bearing field (422, one message each) and more than ``max_refs``
    references. ``slots``: the key paths where the request holds a model."""
    check.nesting("the request", value)   # without recursion: the walk below recurses
    walk = _Walk(stored_file, max_refs)
    if not isinstance(value, dict):
        return walk.plain(value)
    return {k: walk.slot(v, (k,), slots) for k, v in value.items()}


class _Walk:
    def __init__(self, stored_file, max_refs: int | None):
        self.stored_file, self.max_refs, self.refs = stored_file, max_refs, 0

    def plain(self, value: Any) -> Any:
        """Where no model goes: no references, no paths."""
        if isinstance(value, list):
            return [self.plain(v) for v in value]
        if not isinstance(value, dict):
            return value
        if isinstance(value.get("type"), str) and value["type"] in STORED:
            if set(value) - STORED[value["type"]][0]:
                refuse()   # a path is refused as a path, wherever it is
            raise HTTPException(422, MISPLACED)
        return {k: self.plain(_no_path(k, v)) for k, v in value.items()}

    def slot(self, value: Any, path: tuple[str, ...], slots) -> Any:
        """``value`` at key path ``path`` of the request: a model at a slot, plain elsewhere."""
        if path in slots:
            return self.model(value)
        deeper = {s[len(path)] for s in slots if len(s) > len(path) and s[:len(path)] == path}
        if not deeper or not isinstance(value, dict) or (isinstance(value.get("type"), str)
                                                         and value["type"] in STORED):
            return self.plain(value)
        return {k: self.slot(_no_path(k, v), (*path, k), slots) if k in deeper else self.plain(_no_path(k, v))
                for k, v in value.items()}

    def model(self, value: Any) -> Any:
        if not isinstance(value, dict):
            return self.plain(value)
        kind = value.get("type")
        if isinstance(kind, str) and kind in STORED:
            return self.stored(value)
        nested = NESTED_MODELS.get(kind, ()) if isinstance(kind, str) else ()
        out = {}
        for k, v in value.items():
            _no_path(k, v)
            if k in nested:
                out[k] = [self.model(x) for x in v] if isinstance(v, list) else self.model(v)
            else:
                out[k] = self.plain(v)
        return out

    def stored(self, value: dict[str, Any]) -> dict[str, Any]:
        kind = value["type"]
        fields, listing = STORED[kind]
        if set(value) - fields:
            refuse()
        self.refs += 1
        if self.max_refs is not None and self.refs > self.max_refs:
            raise HTTPException(422, f"more than {self.max_refs} stored files named in one request "
                                     "(BSDFLAB_LIMIT_STORE_REFS)")
        h = value.get("hash")
        if not isinstance(h, str) or _HASH.fullmatch(h) is None:
            raise HTTPException(422, f'a {kind} is named by its content hash: {{"type": "{kind}", "hash": '
                                     '"<64 lower-case hex digits>"}')
        path = self.stored_file(kind, h)
        if path is None:
            raise HTTPException(422, f"no {kind} {h} in this server's store ({listing})")
        if kind != "table":
            return dict(value)   # found by its hash in the store folder when the model is built
        return {**{k: v for k, v in value.items() if k != "hash"}, "path": str(path)}


def _no_path(key: str, value: Any) -> Any:
    if key in PATH_FIELDS and value is not None and not isinstance(value, (bool, int, float)):
        refuse()
    return value


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
