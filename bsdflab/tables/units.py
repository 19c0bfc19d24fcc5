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
from bsdflab.tables.data import TableGrid
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


# -- the driver -------------------------------------------------------------------------------
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
