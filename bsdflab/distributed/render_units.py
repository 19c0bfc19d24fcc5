"""Rendering as work units: (pixel band, pass) → that pass's sums over the band.

A unit is a pure function of (scene dict, render settings, band, pass): the C++ job seeds
every (pixel, pass) from the render seed, so a unit computes exactly the numbers the local
renderer computes for those pixels in that pass, on any worker, on every retry. The driver
adds units pass by pass in order — the local renderer's own order of additions — so the
distributed image equals the local one bit for bit (tests/test_distributed.py).

What crosses the wire: the scene as its plain dict (``Scene.to_dict``), the settings as a
dict, and table files as bytes (a tabulated material is resolved once by the driver; each
worker stores the file content-addressed and reads it like any table). No C++ object is
pickled. Workers keep the last built scene, so a scene's BVH is built once per worker.
"""
from __future__ import annotations

import copy
import hashlib
import json
import os
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

# Samples in one unit when the caller does not say: ~0.5-2 s of one core on the snake and
# basic-materials scenes (bench/bench_distributed.py measures per-unit overhead at a few
# ms, so units this size keep it under 1 %).
DEFAULT_UNIT_SAMPLES = 1 << 20


@dataclass(frozen=True)
class RenderUnit:
    index: int
    y0: int
    y1: int
    pass_index: int


def plan_units(width: int, height: int, spp: int, pass_spp: int,
               unit_samples: int = DEFAULT_UNIT_SAMPLES) -> list[RenderUnit]:
    """Bands of whole rows × passes, each about ``unit_samples`` samples; pass-major order, so
    early passes (and a usable preview) complete first."""
    if not isinstance(unit_samples, int) or unit_samples < 1:
        raise ValueError(f"unit_samples must be a positive integer, got {unit_samples!r}")
    passes = (spp + pass_spp - 1) // pass_spp
    rows = max(1, min(height, unit_samples // max(1, width * pass_spp)))
    bands = [(y, min(y + rows, height)) for y in range(0, height, rows)]
    units = []
    for p in range(passes):
        for y0, y1 in bands:
            units.append(RenderUnit(len(units), y0, y1, p))
    return units


def job_settings(scene_dict: dict[str, Any], spp: int, pass_spp: int, seed: int, strategy: int,
                 spectral: bool = False) -> dict[str, Any]:
    return {"spp": int(spp), "pass_spp": int(pass_spp), "seed": int(seed), "strategy": int(strategy),
            "spectral": bool(spectral), "max_depth": int(scene_dict["max_depth"]),
            "rr_depth": int(scene_dict["rr_depth"])}


def resolve_tables(scene, progress: bool, cache_dir, spectral: bool = False) -> tuple[dict[str, Any], dict[str, bytes]]:
    """The scene's dict with every tabulated material replaced by a reference to its table
    file's content hash, and those files' bytes (tabulating missing tables here, once;
    spectral tables for a spectral render, as in-process)."""
    from bsdflab.render.build import TABULATED, resolve_bsdf

    d = scene.to_dict()
    files: dict[str, bytes] = {}

    def swap(bsdf_dict):
        if not isinstance(bsdf_dict, dict) or bsdf_dict.get("type") != TABULATED:
            return bsdf_dict
        table = resolve_bsdf(bsdf_dict, progress=progress, cache_dir=cache_dir, spectral=spectral)
        data = _table_bytes(table)
        digest = hashlib.sha256(data).hexdigest()
        files[digest] = data
        return {"type": "table", "sha256": digest}

    for m in d["materials"].values():
        m["bsdf"] = swap(m["bsdf"])
        if m.get("gap_bsdf") is not None:
            m["gap_bsdf"] = swap(m["gap_bsdf"])
    return d, files


def _table_bytes(table) -> bytes:
    """The table file's bytes: the cache file, or (a cache folder that was not writable)
    the table written to a temporary file here."""
    if table.path is not None:
        return Path(table.path).read_bytes()
    from bsdflab.tables.file_format import write_table

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "table.exr"
        write_table(path, table.table)
        return path.read_bytes()


# -- on the worker -----------------------------------------------------------------------
_lock = threading.Lock()
_built: dict[str, Any] = {}  # key -> RenderJob (one scene at a time per worker)


def _table_dir() -> Path:
    path = Path(tempfile.gettempdir()) / f"bsdflab-dask-tables-{os.getuid()}"
    path.mkdir(parents=True, exist_ok=True)
    return path


def _local_table(digest: str, data: bytes) -> str:
    from bsdflab.util.files import write_atomically

    if hashlib.sha256(data).hexdigest() != digest:
        raise ValueError(f"table bytes do not match their hash {digest}")
    path = _table_dir() / f"{digest}.exr"
    if not path.exists():
        write_atomically(path, lambda tmp: Path(tmp).write_bytes(data), suffix=".exr")
    return str(path)


def _job_for(scene_dict: dict[str, Any], tables: dict[str, bytes], settings: dict[str, Any]):
    from bsdflab import _core
    from bsdflab.render.build import build_render_scene
    from bsdflab.render.scene import Scene

    key = hashlib.sha256(json.dumps([scene_dict, settings], sort_keys=True).encode()).hexdigest()
    with _lock:
        job = _built.get(key)
        if job is not None:
            return job
        d = copy.deepcopy(scene_dict)
        for m in d["materials"].values():
            for name in ("bsdf", "gap_bsdf"):
                b = m.get(name)
                if isinstance(b, dict) and b.get("type") == "table" and "sha256" in b:
                    m[name] = {"type": "table", "path": _local_table(b["sha256"], tables[b["sha256"]])}
        core_scene = build_render_scene(Scene.from_dict(d), progress=False, spectral=settings["spectral"])
        job = _core.RenderJob(core_scene, settings["spp"], settings["pass_spp"], settings["max_depth"],
                              settings["rr_depth"], settings["seed"], 16, settings["strategy"],
                              settings["spectral"])
        _built.clear()
        _built[key] = job
        return job


def render_unit(scene_dict: dict[str, Any], tables: dict[str, bytes], settings: dict[str, Any],
                unit: RenderUnit) -> tuple[np.ndarray, np.ndarray, int]:
    """(sum, sum of squares, invalid samples) of ``unit`` — runs on a worker."""
    job = _job_for(scene_dict, tables, settings)
    width = int(scene_dict["camera"]["width"])
    return job.render_window(0, unit.y0, width, unit.y1, unit.pass_index)
