"""Measure a BSDF into a table: the C++ tabulator on all cores, with a progress bar, or in
blocks of cells on a runner (this process, a Dask cluster).

The method (a pilot stage sets each cell's effort, a finish stage computes its value from
fresh walks) and its public stage functions are in bsdflab.tables.stages; the work units
that split a table over a runner are in bsdflab.tables.units.
"""
from __future__ import annotations

from bsdflab.bsdfs.base import BSDF
from bsdflab.tables.channels import table_channels
from bsdflab.tables.data import TableData, TableGrid, check_table_memory
from bsdflab.tables.stages import (
    DEFAULT_MAX_SAMPLES,
    DEFAULT_MIN_SAMPLES,
    ERROR_FLOOR,
    assemble,
    cell_count,
    finish_cells,
    floor_scale,
    lobes_of,
    pilot_cells,
)
from bsdflab.tables.units import tabulate_adding_doubling_units, tabulate_units
from bsdflab.util import args as check
from bsdflab.util import runners
from bsdflab.util.runners import Runner

__all__ = ["DEFAULT_MAX_SAMPLES", "DEFAULT_MIN_SAMPLES", "ERROR_FLOOR", "METHODS", "tabulate"]

METHODS = ("pfmc", "adding-doubling")


def tabulate(model: BSDF, grid: TableGrid | None = None, rel_error: float = 0.01,
             wavelengths=None, min_samples: int = DEFAULT_MIN_SAMPLES,
             max_samples: int = DEFAULT_MAX_SAMPLES, seed: int = 0,
             progress: bool = True, client=None, film_lookup: bool = True,
             runner: Runner | None = None, method: str = "pfmc") -> TableData:
    """Tabulate ``model`` on ``grid``; returns the table (write it with ``write_table``).

    Parameters
    ----------
    model : BSDF
        Any isotropic bsdflab BSDF; layered models are estimated adaptively.
    grid : TableGrid
        Resolution and film-thickness nodes (nm). Default ``TableGrid()``.
    rel_error : float in (0, 1]
        Target relative standard error per cell (bsdflab.tables.stages).
    wavelengths : None or array of nm
        None stores linear sRGB (D65) from the default spectral grid.
    min_samples, max_samples : int
        Pilot walks per cell (also the least number of final walks), and the cap. PFMC
        walk contributions are heavy-tailed: with ~100 walks a pilot's error estimate is
        usually too small; 512 make it trustworthy (tests/tables/test_tables.py measures this).
    seed : int
        Seed of the walks (per cell, combined with the cell index and stage).
    progress : bool
        Show a tqdm progress bar on stderr.
    runner : bsdflab.util.runners.Runner, optional
        Run the cells in blocks (bsdflab.tables.units) on this runner instead of as one job
        on this process's threads: the same values, errors and sample counts, bit for bit.
    client : dask.distributed.Client, optional
        A convenience for ``runner=DaskRunner(client)`` (bsdflab.distributed).
    film_lookup : bool
        True (default): a walk reads the top film's R and T from a per-thickness-node cubic
        lookup over the cosine (core/include/bsdflab/film_lookup.h; its error, measured
        when it is built, is <= 1e-7 absolute, meta["film_lookup_error"]) instead of the
        Airy sum per wavelength: ~3x fewer CPU-seconds per walk for the snake. False
        evaluates every film exactly (the reference; not available with a runner).
    method : 'pfmc' (default) or 'adding-doubling'
        'adding-doubling' tabulates a reflecting ``Layered`` model deterministically
        (bsdflab.tables.adding_doubling: one solve per thickness node, the solver's error
        bound stored as each cell's error, method and settings in ``meta``); the walk
        settings (samples, seed, film_lookup, runner, client) do not apply to it.

    Runs :func:`pilot_cells`, :func:`floor_scale`, :func:`finish_cells` and
    :func:`assemble` over every cell (bsdflab.tables.stages).
    """
    grid = grid or TableGrid()
    check.real_scalar("rel_error", rel_error, 0.0, 1.0, lo_open=True)
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {check.brief(method)}")
    if method == "adding-doubling":
        from bsdflab.tables.adding_doubling import tabulate_adding_doubling

        check_table_memory(grid, len(table_channels(wavelengths)[0]), 1)
        runner = runners.resolve(runner, client)
        if runner is not None:
            return tabulate_adding_doubling_units(runner, model, grid, rel_error=rel_error,
                                                  wavelengths=wavelengths, progress=progress)
        return tabulate_adding_doubling(model, grid, rel_error=rel_error, wavelengths=wavelengths)
    if check.count("max_samples", max_samples) < check.count("min_samples", min_samples):
        raise ValueError(f"max_samples ({max_samples}) must be >= min_samples ({min_samples})")
    n = cell_count(model, grid)
    # Before the core allocates (docs/limits.md).
    check_table_memory(grid, len(table_channels(wavelengths)[0]), len(lobes_of(model)))
    film_lookup = check.flag("film_lookup", film_lookup)
    runner = runners.resolve(runner, client)
    if runner is not None:
        if not film_lookup:
            raise ValueError("film_lookup=False is not available with a runner (the units use the lookup)")
        return tabulate_units(runner, model, grid, rel_error=rel_error, wavelengths=wavelengths,
                              min_samples=min_samples, max_samples=max_samples,
                              seed=check.seed(seed), progress=progress)
    kw = dict(wavelengths=wavelengths, min_samples=min_samples, seed=seed)
    pilot = pilot_cells(model, grid, range(n), progress=progress, film_lookup=film_lookup, **kw)
    scale = floor_scale(model, grid, pilot, **kw)
    part = finish_cells(model, grid, range(n), pilot, scale, rel_error=rel_error,
                        max_samples=max_samples, progress=progress, film_lookup=film_lookup, **kw)
    table = assemble(model, grid, [part], pilot, rel_error=rel_error, max_samples=max_samples, **kw)
    if not film_lookup:  # the reference: say so (assemble records the default, the lookup)
        table.meta["film_lookup_error"] = None
    return table
