"""Tabulation as work units: blocks of table cells, in the tabulator's two stages.

A block is a run of consecutive cells — whole (lobe, thickness node, θi) slices, all θo × Δφ
of each — so a unit's cost is that of a fixed number of cells. Stage 1 (pilot) runs on every
block; the driver merges the pilots in cell order and reduces the one cross-cell quantity
(the per-lobe error-floor scale) exactly as ``tabulate`` does; stage 2 (finish) runs on
every block with the full pilot and the scale. These are the stage functions of
bsdflab.tables.stages, which ``tabulate`` itself is written with, so the table equals the
in-process one bit for bit (values, errors, sample counts) on any runner
(bsdflab.util.runners: this process, or a Dask cluster). Only ``meta``'s timings differ:
they add the units' own times.

What a unit receives (and what crosses the wire to a cluster): the model's dict, the grid's
dict, the settings, cell-index arrays and the pilot's two arrays; results are numpy arrays.
"""
from __future__ import annotations

import json
import math
import threading
from typing import Any

import numpy as np

from bsdflab.bsdfs.base import from_dict
from bsdflab.tables.data import TableData, TableGrid
from bsdflab.tables.stages import (
    CellBlock,
    PilotBlock,
    assemble,
    cell_count,
    finish_cells,
    floor_scale,
    merge_pilots,
    pilot_cells,
)
from bsdflab.util import args as check
from bsdflab.util.runners import Runner, unit_key

# Cells per unit when the caller does not say: a few seconds of one core for the snake's
# RGB table at 2 % (bench/bench_distributed.py: per-unit overhead of a few ms).
DEFAULT_UNIT_CELLS = 512


def plan_blocks(n_cells: int, slice_cells: int, unit_cells: int = DEFAULT_UNIT_CELLS) -> list[np.ndarray]:
    """Consecutive cell blocks of whole slices (``slice_cells`` = θo × Δφ cells each), about
    ``unit_cells`` cells per block."""
    unit_cells = check.integer("unit_cells", unit_cells, 1, check.MAX_COUNT)
    per_block = max(1, round(unit_cells / slice_cells)) * slice_cells
    return [np.arange(a, min(a + per_block, n_cells), dtype=np.int64) for a in range(0, n_cells, per_block)]


# -- the units (on a worker) ------------------------------------------------------------------
_lock = threading.Lock()
_models: dict[str, Any] = {}


def _model(model_dict: dict[str, Any]):
    key = json.dumps(model_dict, sort_keys=True)
    with _lock:
        if key not in _models:
            _models.clear()  # one model at a time per worker
            _models[key] = from_dict(model_dict)
        return _models[key]


def pilot_unit(model_dict, grid_dict, kw: dict[str, Any], cells: np.ndarray) -> PilotBlock:
    return pilot_cells(_model(model_dict), TableGrid.from_dict(grid_dict), cells, **kw)


def finish_unit(model_dict, grid_dict, kw: dict[str, Any], pilot, scale, cells: np.ndarray) -> CellBlock:
    return finish_cells(_model(model_dict), TableGrid.from_dict(grid_dict), cells, pilot, scale, **kw)


def adding_doubling_unit(model_dict, grid_dict, kw: dict[str, Any], nodes: np.ndarray):
    """The adding-doubling table of the thickness nodes ``nodes`` (indices into the grid's)."""
    from bsdflab.tables.deterministic import tabulate_adding_doubling

    grid = TableGrid.from_dict(grid_dict)
    sub = TableGrid(grid.n_theta_i, grid.n_theta_o, grid.n_phi, tuple(grid.thickness_nm[int(i)] for i in nodes))
    return tabulate_adding_doubling(_model(model_dict), sub, **kw)


# -- the driver -------------------------------------------------------------------------------
def tabulate_adding_doubling_units(runner: Runner, model, grid, *, rel_error: float, wavelengths,
                                   progress: bool = True, nodes: int | None = None, orders: int | None = None):
    """``tabulate(model, grid, method="adding-doubling")`` with the film-thickness nodes
    split over ``runner``'s workers (a unit solves the layers below a rough top once and
    redoes the top per node, so a unit holds a run of nodes, not one); the same values and
    bounds as in this process, assembled along the thickness axis. Without thickness nodes
    the table is one unit."""
    from bsdflab.tables.channels import table_channels
    from bsdflab.tables.deterministic import bound_statistics

    n_nodes = len(grid.thickness_nm)
    units = max(1, min(n_nodes, runner.workers()))
    groups = np.array_split(np.arange(n_nodes, dtype=np.int64), units)  # one empty group: no nodes
    model_dict, grid_dict = model.to_dict(), grid.to_dict()
    wl = None if wavelengths is None else [float(w) for w in np.asarray(wavelengths, float).ravel()]
    kw = {"rel_error": rel_error, "wavelengths": wl, "nodes": nodes, "orders": orders}
    key = f"bsdflab-tabulate-ad-{unit_key(model_dict, grid_dict, kw, units)}"
    parts: dict[int, Any] = {}
    runner.run(adding_doubling_unit, [model_dict, grid_dict, kw], groups,
               lambda g, r: parts.__setitem__(int(g[0]) if len(g) else 0, r), key=key, progress=progress,
               desc="tabulating (adding-doubling)")
    ordered = [parts[k] for k in sorted(parts)]
    first = ordered[0]
    values = np.concatenate([p.values for p in ordered], axis=1)
    stderr = np.concatenate([p.stderr for p in ordered], axis=1)
    samples = np.concatenate([p.samples for p in ordered], axis=1)
    meta = dict(first.meta)
    meta["seconds"] = round(sum(p.meta["seconds"] for p in ordered), 3)
    meta["solver"] = {**first.meta["solver"], "orders": max(p.meta["solver"]["orders"] for p in ordered)}
    errors = [p.meta["film_lookup_error"] for p in ordered if p.meta.get("film_lookup_error") is not None]
    meta["film_lookup_error"] = max(errors) if errors else None
    meta.update(bound_statistics(values.astype(np.float64), stderr.astype(np.float64),
                                 table_channels(wavelengths)[3]))
    meta.update({"units": len(groups), "workers": runner.workers()})
    table = TableData(model=model_dict, grid=grid, lobes=first.lobes, channels=first.channels,
                      split_direct=first.split_direct, values=values, stderr=stderr, samples=samples,
                      rel_error_target=first.rel_error_target, meta=meta)
    table.check()
    return table



def tabulate_units(runner: Runner, model, grid, *, rel_error: float, wavelengths, min_samples: int,
                   max_samples: int, seed: int, progress: bool = True,
                   unit_cells: int = DEFAULT_UNIT_CELLS):
    """``tabulate(model, grid, ...)`` with its cells in blocks on ``runner`` (arguments
    validated by the caller); the same TableData, bit for bit, but for meta's timings."""
    n = cell_count(model, grid)
    blocks = plan_blocks(n, grid.n_theta_o * grid.n_phi, unit_cells)
    model_dict, grid_dict = model.to_dict(), grid.to_dict()
    wl = None if wavelengths is None else [float(w) for w in np.asarray(wavelengths, float).ravel()]
    stage1 = {"wavelengths": wl, "min_samples": min_samples, "seed": seed}
    stage2 = {**stage1, "rel_error": rel_error, "max_samples": max_samples}
    key = f"bsdflab-tabulate-{unit_key(model_dict, grid_dict, stage2, unit_cells)}"

    pilots: list = []
    runner.run(pilot_unit, [model_dict, grid_dict, stage1], blocks, lambda b, r: pilots.append(r),
               key=f"{key}-pilot", progress=progress, desc="tabulating (pilot)")
    pilot = merge_pilots(pilots, n)
    scale = floor_scale(model, grid, pilot, **stage1)
    parts: list = []
    runner.run(finish_unit, [model_dict, grid_dict, stage2, pilot, scale], blocks,
               lambda b, r: parts.append(r), key=f"{key}-finish", progress=progress, desc="tabulating")
    table = assemble(model, grid, parts, pilot, **stage2)
    table.meta.update({"units": 2 * len(blocks), "unit_cells": int(math.ceil(n / len(blocks))),
                       "workers": runner.workers()})
    return table
