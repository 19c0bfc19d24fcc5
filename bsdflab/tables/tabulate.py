"""Measure a BSDF into a table: the C++ tabulator on all cores, with a progress bar.

For layered (PFMC) models the top interface's own reflection is left out of the table
(`split_direct`) and re-evaluated exactly at lookup: it is the sharpest feature and is
known in closed form, so the table only holds the smoother multiply-scattered light.
Effort adapts per cell: a first pass of `min_samples` walks, then each cell is refined
until the standard error of its luminance is below rel_error x max(|luminance|,
5 % of the lobe's mean luminance), capped at `max_samples`.
"""
from __future__ import annotations

import time

import numpy as np

from .. import __version__, _core
from .._jobs import run_with_progress
from .. import _validate as check
from ..bsdfs.base import BSDF
from ..layered import Layered
from ..lobes import Lobe
from .channels import table_channels
from .data import LOBES, TableData, TableGrid, check_table_memory

ERROR_FLOOR = 0.05
SIGNIFICANT = 0.01  # cells counted in the achieved-error statistics: f > 1 % of the max


def tabulate(model: BSDF, grid: TableGrid | None = None, rel_error: float = 0.01,
             wavelengths=None, min_samples: int = 512, max_samples: int = 65536, seed: int = 0,
             progress: bool = True) -> TableData:
    """Tabulate ``model`` on ``grid``; returns the table (write it with ``write_table``).

    Parameters
    ----------
    model : BSDF
        Any isotropic bsdflab BSDF; layered models are estimated adaptively.
    grid : TableGrid
        Resolution and film-thickness nodes (nm). Default ``TableGrid()``.
    rel_error : float in (0, 1]
        Target relative standard error per cell (see module docstring).
    wavelengths : None or array of nm
        None stores linear sRGB (D65) from the default spectral grid.
    min_samples, max_samples : int
        Walks per cell in the first pass, and the cap. PFMC walk contributions are
        heavy-tailed: with ~100 walks a cell's mean is usually low and its standard error
        too small, which then stops refinement early; 512 walks make the first pass's
        error estimate trustworthy (tests/test_tables.py measures this).
    seed : int
        Seed of the walks (per cell, combined with the cell index).
    progress : bool
        Show a tqdm progress bar on stderr.
    """
    if not isinstance(model, BSDF):
        raise ValueError(f"model must be a bsdflab BSDF, got {type(model).__name__}")
    grid = grid or TableGrid()
    rel_error = check.real_scalar("rel_error", rel_error, 0.0, 1.0, lo_open=True)
    min_samples = _count("min_samples", min_samples)
    max_samples = _count("max_samples", max_samples)
    if max_samples < min_samples:
        raise ValueError(f"max_samples ({max_samples}) must be >= min_samples ({min_samples})")
    seed = check.seed(seed)
    names, model_wl, P, lum = table_channels(wavelengths)
    rows = np.vstack([P, lum @ P])
    lobes = LOBES if model.lobes & Lobe.TRANSMISSION else LOBES[:1]
    split = isinstance(model, Layered)
    check_table_memory(grid, len(names), len(lobes))  # before the core allocates (docs/limits.md)

    job = _core.TabulationJob(model._core(model_wl), len(lobes), grid.n_theta_i, grid.n_theta_o,
                              grid.n_phi, list(grid.thickness_nm), list(rows.ravel()), rows.shape[0],
                              rel_error, ERROR_FLOOR, min_samples, max_samples, seed, split)
    start = time.perf_counter()
    run_with_progress(job, progress, unit="cell", desc="tabulating")
    elapsed = time.perf_counter() - start

    shape = (len(lobes), max(1, len(grid.thickness_nm)), grid.n_theta_i, grid.n_theta_o, grid.n_phi)
    values = np.asarray(job.value).reshape(*shape, len(names)).astype(np.float32)
    stderr = np.asarray(job.error).reshape(*shape, len(names)).astype(np.float32)
    samples = np.asarray(job.samples).reshape(shape).astype(np.int32)
    meta = {"bsdflab_version": __version__, "seconds": round(elapsed, 3),
            "threads": _core.worker_count(), "min_samples": min_samples,
            "max_samples": max_samples, "seed": seed, "error_floor": ERROR_FLOOR,
            **achieved_error(np.asarray(job.lum_value), np.asarray(job.lum_error))}
    table = TableData(model=model.to_dict(), grid=grid, lobes=lobes, channels=names,
                      split_direct=split, values=values, stderr=stderr, samples=samples,
                      rel_error_target=rel_error, meta=meta)
    table.check()
    return table


def achieved_error(lum: np.ndarray, lum_err: np.ndarray) -> dict[str, float]:
    """RMS, 95th percentile and max relative standard error of the luminance over the
    cells whose luminance exceeds 1 % of the table's maximum."""
    mask = lum > SIGNIFICANT * max(float(lum.max()), 1e-300)
    if not np.any(mask):
        return {"rel_error_rms": 0.0, "rel_error_p95": 0.0, "rel_error_max": 0.0}
    r = lum_err[mask] / lum[mask]
    return {"rel_error_rms": float(np.sqrt(np.mean(r**2))),
            "rel_error_p95": float(np.percentile(r, 95)), "rel_error_max": float(r.max())}


def _count(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= 1 << 24:
        raise ValueError(f"{name} must be an integer in [1, {1 << 24}], got {value!r}")
    return int(value)
