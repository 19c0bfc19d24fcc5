"""The tabulator's stages: pure functions over blocks of table cells (``tabulate`` in
bsdflab.tables.tabulate runs them; the work units of bsdflab.tables.units run them block by
block on a runner).

For layered (PFMC) models the top interface's own reflection is left out of the table
(`split_direct`: the core tabulates the model's scattered part; for light from below, the
base's own reflection likewise) and re-evaluated exactly at lookup: it is the sharpest
feature and is known in closed form, so the table only holds the smoother
multiply-scattered light.

Effort adapts per cell in two stages (core/include/bsdflab/tabulation.h has the details):

1. **pilot** -- `min_samples` walks per cell estimate its luminance and standard error;
2. **finish** -- each cell gets ``n = clamp(1.1 min_samples (se / target)^2, min_samples,
   max_samples)`` walks with ``target = rel_error x max(|pilot luminance|, 5 % of the
   lobe's mean pilot luminance)``, from a fresh seed stream. The stored value is the mean of
   those fresh walks only, so it is unbiased: the pilot decides the effort, never the value
   (given n, the fresh walks are independent of the pilot). Its standard error pools the
   per-walk spread of the pilot's and the fresh walks (estimator version 7; the fresh
   spread alone under-covered heavy-tailed cells: docs/coverage.md).

Any split of the cells into blocks reproduces ``tabulate`` bit for bit (it is written with
exactly these calls)::

    n = cell_count(model, grid)
    pilots = [pilot_cells(model, grid, block, **kw) for block in blocks]  # any split of range(n)
    pilot = merge_pilots(pilots, n)                        # every cell, in cell order
    scale = floor_scale(model, grid, pilot, **kw)          # the one cross-cell quantity
    parts = [finish_cells(model, grid, block, pilot, scale, **kw) for block in blocks]
    table = assemble(model, grid, parts, pilot, **kw)

where ``kw`` holds the same ``rel_error``, ``wavelengths``, ``min_samples``, ``max_samples``
and ``seed`` everywhere (each function takes the ones it needs). A cell's pilot is a pure
function of (model, grid, cell, settings, seed); its final value also of its pilot and
the floor scale; each cell is computed by one thread, so neither block boundaries nor
thread counts change any bit of values, errors or sample counts.
"""
from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bsdflab import _core
from bsdflab._version import __version__
from bsdflab.bsdfs.base import BSDF
from bsdflab.lobes import Lobe
from bsdflab.tables.channels import table_channels
from bsdflab.tables.data import LOBES, TWO_SIDED_LOBES, TableData, TableGrid
from bsdflab.tables.file_format import canonical_json
from bsdflab.util import args as check
from bsdflab.util.progress import run_with_progress

# The tabulator's defaults are the core's (core/include/bsdflab/tabulation.h), written once.
ERROR_FLOOR = _core.TabulationSettings.default_floor
SIGNIFICANT = 0.01  # cells counted in the achieved-error statistics: f > 1 % of the max
DEFAULT_MIN_SAMPLES = _core.TabulationSettings.default_min_samples
DEFAULT_MAX_SAMPLES = _core.TabulationSettings.default_max_samples


@dataclass(frozen=True)
class PilotBlock:
    """Pilot-stage results for a list of cells (arrays aligned with ``cells``)."""

    cells: np.ndarray      # int64 cell indices (TableGrid cell order)
    lum: np.ndarray        # pilot luminance of f (no cosine)
    lum_error: np.ndarray  # its standard error
    nonfinite: int         # walks whose contribution was not finite (0 for a sound model)
    seconds: float = 0.0
    capped: int = 0        # walks cut by the model's max_depth (biased low; 0 for a sound model)
    error: np.ndarray | None = None  # (n, channels) each channel's standard error (None: not kept)
    min_samples: int | None = None   # the pilot's walks per cell (None: not recorded)


@dataclass(frozen=True)
class CellBlock:
    """Finish-stage results for a list of cells (arrays aligned with ``cells``)."""

    cells: np.ndarray      # int64 cell indices
    values: np.ndarray     # (n, channels) f without cosine
    stderr: np.ndarray     # (n, channels)
    samples: np.ndarray    # (n,) walks behind each value (the fresh walks only)
    lum: np.ndarray        # (n,) luminance of the value
    lum_error: np.ndarray  # (n,)
    nonfinite: int
    seconds: float = 0.0
    capped: int = 0


def cell_count(model: BSDF, grid: TableGrid) -> int:
    """Number of cells of ``model``'s table on ``grid`` (cells are 0 .. n-1)."""
    _check_model(model)
    return len(lobes_of(model)) * max(1, len(grid.thickness_nm)) * grid.n_theta_i * grid.n_theta_o * grid.n_phi


def pilot_cells(model: BSDF, grid: TableGrid, cells, *, wavelengths=None,
                min_samples: int = DEFAULT_MIN_SAMPLES, seed: int = 0,
                progress: bool = False, film_lookup: bool = True) -> PilotBlock:
    """Pilot stage for ``cells`` (a range or 1-D integer array of cell indices).

    Each cell's result depends only on (model, grid, cell, wavelengths, min_samples, seed).
    Runs on all cores with the GIL released; Ctrl-C cancels. ``film_lookup``: as
    :func:`tabulate`'s."""
    tab = _tabulator(model, grid, wavelengths, min_samples=min_samples, max_samples=min_samples, seed=seed,
                     rel_error=0.01, film_lookup=film_lookup)
    idx = _cells(cells, tab.cells)
    job = tab.pilot_job(idx.tolist())
    start = time.perf_counter()
    run_with_progress(job, progress, unit="cell", desc="tabulating (pilot)")
    return PilotBlock(idx, np.asarray(job.pilot_lum), np.asarray(job.pilot_error),
                      int(job.pilot_nonfinite), time.perf_counter() - start, int(job.pilot_capped),
                      np.asarray(job.pilot_channel_error).reshape(len(idx), tab.out_channels), int(min_samples))


def merge_pilots(blocks: Sequence[PilotBlock], n_cells: int) -> PilotBlock:
    """One PilotBlock over all ``n_cells`` cells in cell order from blocks that cover each
    cell exactly once (in any order)."""
    cells = np.concatenate([b.cells for b in blocks]) if blocks else np.zeros(0, np.int64)
    order = _cover(cells, n_cells, "pilot blocks")
    lum = np.concatenate([b.lum for b in blocks])[order]
    err = np.concatenate([b.lum_error for b in blocks])[order]
    channel_err = (np.concatenate([b.error for b in blocks])[order]
                   if blocks and all(b.error is not None for b in blocks) else None)
    efforts = {b.min_samples for b in blocks}
    if len(efforts) > 1:
        raise ValueError(f"pilot blocks ran different min_samples ({sorted(efforts, key=str)}): "
                         "one table, one pilot effort")
    return PilotBlock(np.arange(n_cells, dtype=np.int64), lum, err,
                      sum(b.nonfinite for b in blocks), sum(b.seconds for b in blocks),
                      sum(b.capped for b in blocks), channel_err, efforts.pop() if efforts else None)


def floor_scale(model: BSDF, grid: TableGrid, pilot: PilotBlock, *, wavelengths=None,
                min_samples: int = DEFAULT_MIN_SAMPLES, seed: int = 0) -> np.ndarray:
    """The per-lobe error floor scale (mean |pilot luminance| of the lobe's cells, summed
    in cell order by the core): the one cross-cell input of the finish stage. ``pilot``
    must cover every cell (see :func:`merge_pilots`)."""
    tab = _tabulator(model, grid, wavelengths, min_samples=min_samples, max_samples=min_samples, seed=seed,
                     rel_error=0.01)  # no walks: any film_lookup (True shares the pilot's)
    _full(pilot, tab.cells)
    return np.asarray(tab.floor_scale(pilot.lum.tolist()))


def finish_cells(model: BSDF, grid: TableGrid, cells, pilot: PilotBlock, scale, *,
                 rel_error: float = 0.01, wavelengths=None, min_samples: int = DEFAULT_MIN_SAMPLES,
                 max_samples: int = DEFAULT_MAX_SAMPLES, seed: int = 0,
                 progress: bool = False, film_lookup: bool = True) -> CellBlock:
    """Finish stage for ``cells``: the effort from each cell's pilot and ``scale``, the
    values from fresh walks. ``pilot`` must cover every cell (:func:`merge_pilots`);
    ``scale`` is :func:`floor_scale`'s result. Runs on all cores, GIL released."""
    rel_error = check.real_scalar("rel_error", rel_error, 0.0, 1.0, lo_open=True)
    tab = _tabulator(model, grid, wavelengths, min_samples=min_samples, max_samples=max_samples, seed=seed,
                     rel_error=rel_error, film_lookup=film_lookup)
    idx = _cells(cells, tab.cells)
    _full(pilot, tab.cells)
    # the finish reads min_samples as the pilot's walk count (its effort rule and the pooled
    # errors' pilot weight): a pilot of another effort would give every cell a wrong error
    if pilot.min_samples is not None and pilot.min_samples != tab.settings.min_samples:
        raise ValueError(f"min_samples ({tab.settings.min_samples}) must be the pilot's "
                         f"({pilot.min_samples}): the finish pools the pilot's walks by that count")
    scale = np.asarray(scale, dtype=np.float64).ravel()
    if scale.shape != (len(lobes_of(model)),) or not np.all(np.isfinite(scale)):
        raise ValueError(f"scale must hold one finite value per lobe ({len(lobes_of(model))}), got {scale!r}")
    # the pilot's channel errors pool into the cells' errors (estimator version 7; without
    # them each channel takes the luminance's pooled/fresh ratio)
    channel_err = [] if pilot.error is None else np.asarray(pilot.error, np.float64)[idx].ravel().tolist()
    job = tab.finish_job(idx.tolist(), pilot.lum[idx].tolist(), pilot.lum_error[idx].tolist(), scale.tolist(),
                         pilot_channel_error=channel_err)
    start = time.perf_counter()
    run_with_progress(job, progress, unit="cell", desc="tabulating")
    C = tab.out_channels
    return CellBlock(idx, np.asarray(job.value).reshape(len(idx), C), np.asarray(job.error).reshape(len(idx), C),
                     np.asarray(job.samples), np.asarray(job.lum_value), np.asarray(job.lum_error),
                     int(job.nonfinite), time.perf_counter() - start, int(job.capped))


def assemble(model: BSDF, grid: TableGrid, blocks: Sequence[CellBlock], pilot: PilotBlock, *,
             rel_error: float = 0.01, wavelengths=None, min_samples: int = DEFAULT_MIN_SAMPLES,
             max_samples: int = DEFAULT_MAX_SAMPLES, seed: int = 0) -> TableData:
    """The TableData from finish blocks covering every cell exactly once (any order) and
    the full pilot. ``meta`` records the settings, the summed stage times, the walks of
    both stages, the non-finite and the capped (max_depth) walk counts and the achieved error."""
    names, _, _, _ = table_channels(wavelengths)
    lobes = lobes_of(model)
    n = cell_count(model, grid)
    cells = np.concatenate([b.cells for b in blocks]) if blocks else np.zeros(0, np.int64)
    order = _cover(cells, n, "finish blocks")
    _full(pilot, n)
    cat = lambda name: np.concatenate([getattr(b, name) for b in blocks])[order]  # noqa: E731
    shape = (len(lobes), max(1, len(grid.thickness_nm)), grid.n_theta_i, grid.n_theta_o, grid.n_phi)
    values = cat("values").reshape(*shape, len(names)).astype(np.float32)
    stderr = cat("stderr").reshape(*shape, len(names)).astype(np.float32)
    samples = cat("samples").reshape(shape).astype(np.int32)
    nonfinite = int(pilot.nonfinite + sum(b.nonfinite for b in blocks))
    capped = int(pilot.capped + sum(b.capped for b in blocks))
    stochastic = _is_stochastic(model)
    meta = {"bsdflab_version": __version__, "estimator_version": int(_core.estimator_version),
            "seconds": round(pilot.seconds + sum(b.seconds for b in blocks), 3),
            "threads": _core.worker_count(), "min_samples": int(min_samples),
            "max_samples": int(max_samples), "seed": int(seed), "error_floor": ERROR_FLOOR,
            "pilot_walks": int(min_samples) * n if stochastic else 0,
            "nonfinite_walks": nonfinite, "capped_walks": capped,
            "film_lookup_error": _film_lookup_error(model, grid, wavelengths),
            **achieved_error(cat("lum"), cat("lum_error")),
            "rel_error_by_part": by_part(lobes, cat("lum"), cat("lum_error"), achieved_error)}
    table = TableData(model=model.to_dict(), grid=grid, lobes=lobes, channels=names,
                      split_direct=_splits(model), values=values, stderr=stderr, samples=samples,
                      rel_error_target=float(rel_error), meta=meta)
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


def by_part(lobes, lum: np.ndarray, lum_err: np.ndarray, statistics) -> dict[str, dict[str, float]]:
    """``statistics(lum, lum_err)`` of each part (lobe) alone, by name: the same figures as
    the table's, per part (cells are lobe-major, so each part is one contiguous run)."""
    n = len(lobes)
    return {name: statistics(l, e) for name, l, e in zip(lobes, np.split(np.asarray(lum), n),
                                                         np.split(np.asarray(lum_err), n))}


# -- internals ------------------------------------------------------------------------------
def _check_model(model) -> None:
    if not isinstance(model, BSDF):
        raise ValueError(f"model must be a bsdflab BSDF, got {type(model).__name__}")


def lobes_of(model: BSDF) -> tuple[str, ...]:
    """The table's lobes for ``model``: reflection; for a model that transmits also
    transmission, and reflection and transmission of light from below (a two-sided table:
    the walks start below as readily as above)."""
    return TWO_SIDED_LOBES if model.lobes & Lobe.TRANSMISSION else LOBES[:1]


def _splits(model: BSDF) -> bool:
    """Whether the table leaves the model's exactly known part out (layered models)."""
    return getattr(model, "exact_part", None) is not None


def _is_stochastic(model: BSDF) -> bool:
    return hasattr(model, "estimate")


def _core_model(model: BSDF, wavelengths: np.ndarray):
    """The core model the table holds: a layered model's scattered part, else the model."""
    core = model._core(wavelengths)
    return core.scattered_part() if _splits(model) else core


_built_lock = threading.Lock()
_built: dict = {}  # the last table's core tabulator, by (model, grid, channels, film_lookup)


def _tabulator(model, grid, wavelengths, *, min_samples, max_samples, seed, rel_error, film_lookup=True):
    """The core tabulator with these settings. Its model, grid and film lookups are built
    once per table (the last one is kept): the stages differ only in their settings,
    which ``with_settings`` swaps without rebuilding anything."""
    _check_model(model)
    if not isinstance(grid, TableGrid):
        raise ValueError(f"grid must be a TableGrid, got {type(grid).__name__}")
    min_samples = check.count("min_samples", min_samples)
    max_samples = check.count("max_samples", max_samples)
    if max_samples < min_samples:
        raise ValueError(f"max_samples ({max_samples}) must be >= min_samples ({min_samples})")
    settings = _core.TabulationSettings(rel_error=rel_error, floor=ERROR_FLOOR, min_samples=min_samples,
                                        max_samples=max_samples, seed=check.seed(seed),
                                        film_lookup=check.flag("film_lookup", film_lookup))
    wl = None if wavelengths is None else tuple(np.asarray(wavelengths, dtype=np.float64).ravel().tolist())
    key = (id(model), canonical_json(grid.to_dict()), wl, settings.film_lookup)
    with _built_lock:
        held = _built.get(key)
        if held is None or held[0] is not model:  # id() reused by another object
            _built.clear()
            held = _built[key] = (model, _build_tabulator(model, grid, wavelengths, settings))
    return held[1].with_settings(settings)


def _build_tabulator(model, grid, wavelengths, settings):
    _, model_wl, P, lum = table_channels(wavelengths)
    rows = np.vstack([P, lum @ P])
    return _core.Tabulator(_core_model(model, model_wl), n_lobes=len(lobes_of(model)), n_theta_i=grid.n_theta_i,
                           n_theta_o=grid.n_theta_o, n_phi=grid.n_phi, thickness_nm=list(grid.thickness_nm),
                           P=list(rows.ravel()), rows=rows.shape[0], settings=settings)


def _film_lookup_error(model, grid, wavelengths) -> float | None:
    """The largest measured error of the film lookups the walks used (None: none used)."""
    if not _is_stochastic(model):
        return None
    err = _tabulator(model, grid, wavelengths, min_samples=1, max_samples=1, seed=0, rel_error=0.01).film_lookup_error
    return float(err) if err >= 0 else None


def _cells(cells, n: int) -> np.ndarray:
    if isinstance(cells, range):
        idx = np.arange(cells.start, cells.stop, cells.step, dtype=np.int64)
    else:
        a = np.asarray(cells)
        if a.ndim != 1 or (a.size and not np.issubdtype(a.dtype, np.integer)):
            raise ValueError("cells must be a range or a 1-D array of integer cell indices")
        idx = a.astype(np.int64)
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise ValueError(f"cells must lie in [0, {n}), got indices from {idx.min()} to {idx.max()}")
    return idx


def _cover(cells: np.ndarray, n: int, what: str) -> np.ndarray:
    """The permutation that sorts `cells`, which must be each of 0..n-1 exactly once."""
    order = np.argsort(cells, kind="stable")
    if len(cells) != n or not np.array_equal(cells[order], np.arange(n)):
        raise ValueError(f"the {what} must cover each of the {n} cells exactly once")
    return order


def _full(pilot: PilotBlock, n: int) -> None:
    if not isinstance(pilot, PilotBlock) or not np.array_equal(pilot.cells, np.arange(n)):
        raise ValueError(f"pilot must be a PilotBlock over all {n} cells in order (merge_pilots)")
