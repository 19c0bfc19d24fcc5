"""Which client may see an artefact derived from uploads.

An uploaded measured file is private to the clients that uploaded it (bsdflab.service.deps
``model_spec``), and so is what is made from it: a table of it holds its values, a render
shows them. An artefact's hash is derived from its request, and a tenant that knows (or
guesses) an upload's hash can compute the artefact's; so a table or render that names
uploads, directly or through the tables it names, is shown only to a client that uploaded
every one of them (or an admin), and to anyone else is as absent. Artefacts of presets and
inline models name no upload and stay shared by their hash. (A fit's own data files:
bsdflab.service.routers.fits ``_may_read``.)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

UPLOADED = ("measured", "merl")  # the model types named by an upload's hash
MAX_DEPTH = 8  # tables naming tables; deeper is refused to tenants
UNREADABLE = ""  # an upload no client holds (past MAX_DEPTH)


def uploads_in(jobs, value: Any) -> set[str]:
    """The hashes of the uploads ``value`` (a request, a model) derives from: its measured
    and MERL models, and those of every stored table it names (by hash, or by the store
    path a resolved request holds), read from the table's record or file header."""
    found: set[str] = set()
    tables: set[str] = set()

    def walk(v: Any, depth: int) -> None:
        if isinstance(v, list):
            for x in v:
                walk(x, depth)
            return
        if not isinstance(v, dict):
            return
        kind = v.get("type")
        if kind in UPLOADED and isinstance(v.get("hash"), str):
            found.add(v["hash"])
        elif kind == "table":
            key = (
                v.get("hash")
                if isinstance(v.get("hash"), str)
                else (Path(v["path"]).stem if isinstance(v.get("path"), str) else None)
            )
            if key is not None and key not in tables:
                tables.add(key)
                if depth >= MAX_DEPTH:
                    found.add(UNREADABLE)
                else:
                    result = jobs.table(key)
                    if result is not None:
                        walk(result.get("model"), depth + 1)
        for x in v.values():
            walk(x, depth)

    walk(value, 0)
    return found


def may_read(jobs, value: Any, client) -> bool:
    """Whether ``client`` uploaded every upload ``value`` derives from (an admin: always)."""
    if client.admin:
        return True
    return all(h != UNREADABLE and jobs.store.uploaded(h, client.name) for h in uploads_in(jobs, value))
