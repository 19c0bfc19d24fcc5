"""Measure a BSDF into a table: the C++ tabulator on all cores, with a progress bar, or in
blocks of cells on a runner (this process, a Dask cluster).

The method (a pilot stage sets each cell's effort, a finish stage computes its value from
fresh walks) and its public stage functions are in bsdflab.tables.stages; the work units
that split a table over a runner are in bsdflab.tables.units.
"""
from __future__ import annotations

from bsdflab.bsdfs.base import BSDF
from bsdflab.tables.data import TableData, TableGrid, check_table_memory
from bsdflab.tables.request import DEFAULT_REL_ERROR, METHODS, TableRequest
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

__all__ = ["DEFAULT_MAX_SAMPLES", "DEFAULT_MIN_SAMPLES", "DEFAULT_REL_ERROR", "ERROR_FLOOR", "METHODS",
           "make_table", "tabulate"]


def tabulate(model: BSDF, grid: TableGrid | None = None, rel_error: float = DEFAULT_REL_ERROR,
             wavelengths=None, min_samples: int = DEFAULT_MIN_SAMPLES,
             max_samples: int = DEFAULT_MAX_SAMPLES, seed: int = 0,
             progress: bool = True, client=None, film_lookup: bool = True,
             runner: Runner | None = None, method: str = "pfmc", nodes: int | None = None,
             orders: int | None = None) -> TableData:
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
    method : 'pfmc' (default), 'adding-doubling' or 'auto'
        'adding-doubling' tabulates a ``Layered`` model deterministically (reflecting, or
        transmitting with every pair solved, e.g. a smooth top over a smooth or rough
        dielectric base: a two-sided table)
        (bsdflab.tables.deterministic: one solve per thickness node, the solver's error
        bound stored as each cell's error, method and settings in ``meta``); the walk
        settings (samples, seed, film_lookup) do not apply to it. 'auto' (the default of a
        ``TableRequest``, hence of the CLI, jobs and renders) picks adding-doubling wherever
        it covers the model and PFMC otherwise (bsdflab.tables.request).
    nodes, orders : int, optional
        The adding-doubling solver's Gauss-Legendre nodes per panel and Fourier orders
        (default: the table settings of bsdflab.tables.deterministic).

    Validates everything through ``TableRequest.make`` and runs :func:`make_table`, which
    runs :func:`pilot_cells`, :func:`floor_scale`, :func:`finish_cells` and
    :func:`assemble` over every cell (bsdflab.tables.stages).
    """
    request = TableRequest.make(model, grid, rel_error, wavelengths, method, min_samples, max_samples, seed,
                                nodes, orders)
    return make_table(request, progress=progress, runner=runners.resolve(runner, client),
                      film_lookup=check.flag("film_lookup", film_lookup))


def make_table(request: TableRequest, progress: bool = True, runner: Runner | None = None,
               film_lookup: bool = True) -> TableData:
    """The table ``request`` asks for, tabulated by its method (on ``runner`` when given)."""
    model, grid, rel_error, wavelengths = request.model, request.grid, request.rel_error, request.wavelengths
    if request.method == "adding-doubling":
        from bsdflab.tables.deterministic import check_adding_doubling, tabulate_adding_doubling

        check_adding_doubling(model)
        check_table_memory(grid, len(request.channels), len(lobes_of(model)))
        solver = {"nodes": request.nodes, "orders": request.orders}
        if runner is not None:
            return tabulate_adding_doubling_units(runner, model, grid, rel_error=rel_error,
                                                  wavelengths=wavelengths, progress=progress, **solver)
        return tabulate_adding_doubling(model, grid, rel_error=rel_error, wavelengths=wavelengths, **solver)
    n = cell_count(model, grid)
    # Before the core allocates (docs/limits.md).
    check_table_memory(grid, len(request.channels), len(lobes_of(model)))
    min_samples, max_samples, seed = request.min_samples, request.max_samples, request.seed
    if runner is not None:
        if not film_lookup:
            raise ValueError("film_lookup=False is not available with a runner (the units use the lookup)")
        return tabulate_units(runner, model, grid, rel_error=rel_error, wavelengths=wavelengths,
                              min_samples=min_samples, max_samples=max_samples, seed=seed, progress=progress)
    kw = dict(wavelengths=wavelengths, min_samples=min_samples, seed=seed)
    pilot = pilot_cells(model, grid, range(n), progress=progress, film_lookup=film_lookup, **kw)
    scale = floor_scale(model, grid, pilot, **kw)
    part = finish_cells(model, grid, range(n), pilot, scale, rel_error=rel_error,
                        max_samples=max_samples, progress=progress, film_lookup=film_lookup, **kw)
    table = assemble(model, grid, [part], pilot, rel_error=rel_error, max_samples=max_samples, **kw)
    if not film_lookup:  # the reference: say so (assemble records the default, the lookup)
        table.meta["film_lookup_error"] = None
    return table
