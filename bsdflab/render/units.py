"""Rendering as work units: (pixel band, pass) → that pass's sums over the band.

A unit is a pure function of (scene dict, render settings, band, pass): the C++ job seeds
every (pixel, pass) from the render seed, so a unit computes exactly the numbers the local
renderer computes for those pixels in that pass, on any worker, on every retry. The driver
adds units pass by pass in order — the local renderer's own order of additions — so the
image equals the in-process one bit for bit on any runner (bsdflab.util.runners: this
process, or a Dask cluster; tests/distributed/test_distributed.py).

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
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.render.build import TABULATED, build_render_scene, resolve_bsdf
from bsdflab.render.result import RenderResult, render_result
from bsdflab.render.scene import Scene
from bsdflab.tables.file_format import write_table
from bsdflab.util import args as check
from bsdflab.util.files import write_atomically
from bsdflab.util.runners import Runner, unit_key

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
    unit_samples = check.integer("unit_samples", unit_samples, 1, 1 << 62)
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
    if hashlib.sha256(data).hexdigest() != digest:
        raise ValueError(f"table bytes do not match their hash {digest}")
    path = _table_dir() / f"{digest}.exr"
    if not path.exists():
        write_atomically(path, lambda tmp: Path(tmp).write_bytes(data), suffix=".exr")
    return str(path)


def _job_for(scene_dict: dict[str, Any], tables: dict[str, bytes], settings: dict[str, Any]):
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


# -- the driver -------------------------------------------------------------------------------
def render_units(runner: Runner, scene: Scene, spp: int, seed: int, pass_spp: int, strategy: int,
                 spectral: bool = False, progress: bool = True, cache_dir=None,
                 unit_samples: int = DEFAULT_UNIT_SAMPLES, progress_callback=None,
                 cancelled=None) -> RenderResult:
    """Render ``scene`` (validated by the caller) in units on ``runner``; returns the
    RenderResult the in-process renderer would, bit for bit (module docstring)."""
    scene_dict, tables = resolve_tables(scene, progress, cache_dir, spectral=spectral)
    settings = job_settings(scene_dict, spp, pass_spp, seed, strategy, spectral)
    width, height = scene.camera.width, scene.camera.height
    units = plan_units(width, height, spp, pass_spp, unit_samples)
    passes = units[-1].pass_index + 1
    bands = sorted({(u.y0, u.y1) for u in units})

    total = np.zeros((height, width, 3)), np.zeros((height, width, 3))
    # Units arrive in any order; each band adds its passes strictly in order (the local
    # renderer's order of floating-point additions), holding early arrivals until then.
    next_pass = {b: 0 for b in bands}
    waiting: dict[tuple[int, int], dict[int, tuple]] = {b: {} for b in bands}
    invalid = 0

    def add(unit, value):
        nonlocal invalid
        band = (unit.y0, unit.y1)
        waiting[band][unit.pass_index] = value
        while next_pass[band] in waiting[band]:
            s, q, bad = waiting[band].pop(next_pass[band])
            total[0][band[0]:band[1]] += s
            total[1][band[0]:band[1]] += q
            invalid += int(bad)
            next_pass[band] += 1

    start = time.perf_counter()
    runner.run(render_unit, [scene_dict, tables, settings], units, add,
               key=f"bsdflab-render-{unit_key(scene_dict, settings, sorted(tables), unit_samples)}",
               progress=progress, desc="rendering", progress_callback=progress_callback,
               cancelled=cancelled)
    seconds = time.perf_counter() - start
    if any(n != passes for n in next_pass.values()):
        raise RuntimeError("render units: a band is missing passes")  # a driver bug, never input
    mean, variance = _core.RenderJob.finish_image(total[0], total[1], float(spp))
    return render_result(scene, mean, variance, spp, seconds, invalid, seed, spectral,
                         units=len(units), workers=runner.workers())
