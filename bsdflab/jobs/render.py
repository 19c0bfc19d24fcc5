"""Job kind "render": path-trace a named scene to an EXR (linear) and a PNG (sRGB).

Request (normalised)::

    {"scene": "sphere", "options": {...the scene's own keywords...}, "width": 320,
     "height": 180, "spp": 16, "seed": 0, "max_depth": null}

plus ``"lights": [...]`` (light dicts, bsdflab.render.lights) added to the scene's own, kept
only when non-empty (so requests without lights keep their keys).

Artefacts in ``out_dir`` (a content-addressed folder): ``<key>.exr`` and ``<key>.png``.
Tables the scene's materials need are built into, or reused from, the table cache
(``bsdflab.tables.cache.cache_dir()``: ``BSDFLAB_CACHE_DIR`` or the CLI's), by the table
request's method ("auto" unless the material says: adding-doubling wherever it covers the
model), so a table made by ``bsdflab tabulate``, a table job or an earlier render is one
file. The summary's ``tables`` entry (JSON) lists them: each table's hash, method,
``from_cache`` (reused, not made) and ``target_met``.
"""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

from bsdflab import _core
from bsdflab.jobs.keys import job_key, plain_json
from bsdflab.render import render, write_exr, write_png
from bsdflab.render.build import TABULATED, table_request
from bsdflab.render.lights import lights_of
from bsdflab.render.render import MAX_SPP
from bsdflab.scenes import SCENES, scene
from bsdflab.tables.cache import cache_dir, get
from bsdflab.util import args as check
from bsdflab.util.progress import monitored

FIELDS = {"scene", "options", "width", "height", "spp", "seed", "max_depth", "lights"}
MAX_SIDE = 16384


def build_scene(request: dict[str, Any]):
    """The ``bsdflab.render.Scene`` a normalised request describes."""
    s = scene(request["scene"], width=request["width"], height=request["height"], **request["options"])
    if request.get("lights"):
        s = replace(s, lights=(*s.lights, *lights_of(request["lights"])))
    return s if request["max_depth"] is None else replace(s, max_depth=request["max_depth"])


def normalise(request: dict[str, Any]) -> dict[str, Any]:
    unknown = set(request) - FIELDS
    if unknown:
        raise ValueError(f"unknown render request fields: {', '.join(sorted(unknown))}")
    name = request.get("scene")
    if name not in SCENES:
        raise ValueError(f"unknown scene {name!r}; known scenes: {', '.join(SCENES)}")
    options = request.get("options") or {}
    if not isinstance(options, dict) or {"width", "height"} & set(options):
        raise ValueError("options must be a dict of the scene's keywords (width and height go outside it)")
    out = {"scene": name, "options": dict(options),
           "width": check.integer("width", request.get("width", 320), 1, MAX_SIDE),
           "height": check.integer("height", request.get("height", 180), 1, MAX_SIDE),
           "spp": check.integer("spp", request.get("spp", 16), 1, MAX_SPP),
           "seed": check.seed(request.get("seed", 0)),
           "max_depth": request.get("max_depth")}
    if out["max_depth"] is not None:
        out["max_depth"] = check.integer("max_depth", out["max_depth"], 1, 1024)
    if request.get("lights"):
        out["lights"] = [light.to_dict() for light in lights_of(request["lights"])]
    try:
        scene = build_scene(out)   # the scene's own checks (options, materials)
    except ValueError as e:
        if isinstance(options.get("material"), dict) and str(e).startswith("material"):
            raise ValueError(f"options.{e}") from None   # the request's field
        raise
    out["max_depth"] = scene.max_depth
    plain_json(out, "render")  # options must be plain JSON
    return out


def key(request: dict[str, Any]) -> str:
    """SHA-256 of the canonical request, the kind, the package version and the core's
    estimator version: a layered material renders through PFMC's walks (or tables they
    made), so a new estimator version renders anew instead of serving the old image."""
    return job_key("render", {**request, "estimator_version": int(_core.estimator_version)})


def files(request_key: str) -> dict[str, str]:
    return {"exr": f"{request_key}.exr", "png": f"{request_key}.png"}


def existing(request: dict[str, Any], out_dir: Path) -> dict[str, Any] | None:
    k = key(request)
    names = files(k)
    exr, png = Path(out_dir) / names["exr"], Path(out_dir) / names["png"]
    if not (exr.is_file() and png.is_file()):   # both are written atomically, the EXR last
        return None
    try:
        return {"hash": k, "files": names, "from_cache": True, "summary": exr_attributes(exr)}
    except Exception:   # noqa: BLE001 -- an unreadable file is rebuilt, not served
        return None


def run(request: dict[str, Any], out_dir: Path, progress, cancelled, runner=None) -> dict[str, Any]:
    out_dir = Path(out_dir)
    found = existing(request, out_dir)
    if found is not None:
        return found
    k = key(request)
    names = files(k)
    exr, png = out_dir / names["exr"], out_dir / names["png"]

    tabulated = False

    def staged(stage: str, fraction: float) -> None:
        # Tables first (when a material needs one), then the image: one bar from 0 to 1.
        nonlocal tabulated
        if stage == "tabulating":
            tabulated = True
            progress(0.5 * fraction)
        else:
            progress(0.5 + 0.5 * fraction if tabulated else fraction)

    scene = build_scene(request)
    tables_dir = cache_dir()
    with monitored(staged, cancelled):
        tables = scene_tables(scene, tables_dir)
        result = render(scene, spp=request["spp"], seed=request["seed"], progress=False,
                        cache_dir=tables_dir, runner=runner)
    summary = {k2: str(v) for k2, v in result.summary().items()}
    if tables:
        summary["tables"] = json.dumps(tables)
    write_png(png, result.mean)
    write_exr(exr, result.mean, summary)
    return {"hash": k, "files": names, "from_cache": False, "summary": summary}


def scene_tables(scene, folder: Path) -> list[dict[str, Any]]:
    """The tables ``scene``'s materials need, each read from the cache ``folder`` or made
    into it (once per table): hash, method, whether it was reused, whether it met its
    target. The render then reads them from the cache."""
    found: dict[str, dict[str, Any]] = {}
    for material in scene.materials.values():
        for d in (material.bsdf, material.gap_bsdf):
            if not (isinstance(d, dict) and d.get("type") == TABULATED):
                continue
            table_req = table_request(d)   # an RGB render (as the job renders)
            k = table_req.key()
            if k not in found:
                table, _, hit = get(table_req, cache=folder)
                found[k] = {"hash": k, "method": table_req.method, "from_cache": bool(hit),
                            "target_met": bool(table.accuracy()["target_met"])}
    return list(found.values())


def exr_attributes(path: str | Path) -> dict[str, str]:
    """The ``bsdflab.*`` header attributes of a rendered EXR (the render summary)."""
    import OpenEXR

    header = OpenEXR.File(str(path), header_only=True).header()
    return {k[len("bsdflab."):]: str(v) for k, v in header.items() if k.startswith("bsdflab.")}
