"""Tables by adding-doubling: every cell of a layered model's table from one
deterministic solve (bsdflab.solvers; with a rough top, what lies below it is solved once
and shared by every film-thickness node, only the top is redone), in the same format as the
PFMC tabulator's (the top's own reflection left out, ``split_direct``), with the method,
the solver's settings and its a-posteriori error bound in the header (``meta``).

The stored ``stderr`` of each cell is the solver's deterministic bound (the change to a
solve with half the nodes, 2/3 of the orders and a 16 x thicker doubling start,
``Solution.eval_with_error``), not a standard error; ``meta["error_kind"]`` says so. It
misses the fine-step error of a rough top with alpha >= 0.1 at ``table_settings``' fine step
0.5 (the sub-panels' 0.05 rad clamp; docs/known_limits.md).
A transmissive stack whose every pair the solver solves (``solves_every_pair`` in
bsdflab.solvers.adding_doubling, the solver's own rule: a smooth or rough top, with or
without a film, over a smooth dielectric base or a rough one with no smooth interior
interface between unequal indices above it, and an index contrast at a rough base of at
least ``MIN_EXIT_CONTRAST``) gets a two-sided table (four lobes: reflection and
transmission of light from above and from below; a rough base's own reflection from below
left out, as the top's from above, and added back at lookup); other transmissive stacks
raise ValueError (PFMC tabulates them).
"""
from __future__ import annotations

import copy
import time

import numpy as np

from bsdflab import _core
from bsdflab._version import __version__
from bsdflab.bsdfs.base import from_dict
from bsdflab.layered import Layered
from bsdflab.solvers import solve
from bsdflab.solvers.adding_doubling import (
    MIN_EXIT_CONTRAST,
    Settings,
    base_contrast,
    check_model,
    exit_gap_reason,
    solves_every_pair,
)
from bsdflab.tables.channels import table_channels
from bsdflab.tables.data import DEFAULT_REL_ERROR, LOBES, TWO_SIDED_LOBES, TableData, TableGrid
from bsdflab.tables.stages import by_part

LOBES_BY_COUNT = {1: LOBES[:1], 2: LOBES, 4: TWO_SIDED_LOBES}

METHOD = "adding-doubling"
TABLE_NODES = 16    # Gauss-Legendre nodes per cosine panel of a table's solve
SIGNIFICANT = 0.01  # cells in the error statistics: luminance > 1 % of the max
TABLE_THIN_DEPTH = 2.0 ** -12  # Richardson start error ~1e-5 (docs/solvers.md, convergence)
SPECTRAL_STRIDE = 4  # what lies below a rough top: every 4th of >= 32 wavelengths (20 nm)
# table_settings' rules, in the cache key (solver_settings): a change makes new tables.
TABLE_RULES = ("orders to rel_error/20 (<= 1e-3), start 2^-12, stride 4 from 32 wavelengths, "
               "fine step alpha/2 (alpha/4 below 0.5 %)")


def table_settings(rel_error: float, n_wavelengths: int) -> dict:
    """The solver's truncations for a table of target ``rel_error``: the accuracy a table
    needs, not the solver's 1e-6 defaults (docs/solvers.md, "Tables by adding-doubling").

    Henyey-Greenstein orders to rel_error / 20 of the largest coefficient (at most 1e-3),
    a 2^-12 doubling start, for many wavelengths the stack below a rough top solved at
    every 4th, and the top's fine sub-panels alpha / 2 wide (alpha / 4 below 0.5 %). Each
    truncation is still checked by the coarser solve of ``eval_with_error``."""
    return {"order_tolerance": float(np.clip(rel_error / 20.0, 1e-6, 1e-3)), "thin_depth": TABLE_THIN_DEPTH,
            "spectral_stride": SPECTRAL_STRIDE if n_wavelengths >= 8 * SPECTRAL_STRIDE else 1,
            "fine_step": 0.5 if rel_error >= 0.005 else 0.25}


def with_film_thickness(model: Layered, thickness_nm: float) -> Layered:
    """The model with its top film's total thickness set to ``thickness_nm`` (every layer
    scaled in proportion, as a per-query film thickness does; the other boundaries keep
    their own films, as there); negative: the model."""
    if thickness_nm < 0:
        return model
    d = copy.deepcopy(model.to_dict())
    film = d["interfaces"][0].get("film") or []
    total = sum(layer["thickness_nm"] for layer in film)
    if not film or total <= 0:
        return model
    for layer in film:
        layer["thickness_nm"] = layer["thickness_nm"] * thickness_nm / total
    return from_dict(d)


def adding_doubling_gap(model) -> str | None:
    """Why this method cannot tabulate ``model`` (None: it can): it tabulates ``Layered``
    stacks within the solver's validated range (bsdflab.solvers.adding_doubling
    ``check_model``) that reflect only, or transmit and have every pair solved (the
    solver's ``solves_every_pair``: a two-sided table needs light from below too)."""
    if not isinstance(model, Layered):
        return f"it tabulates Layered models, not {type(model).__name__}"
    try:
        check_model(model)
    except ValueError as e:
        return str(e)
    if _transmits(model) and not solves_every_pair(model):
        return (f"the stack transmits through {exit_gap_reason(model)}, where the solver refuses the pairs below "
                "([rough-exit]), and a table of a transmissive stack holds light from below and transmission")
    contrast = base_contrast(model) if _transmits(model) else None
    if contrast is not None and contrast < MIN_EXIT_CONTRAST:
        return (f"the rough base's index contrast {contrast:.3g} is below {MIN_EXIT_CONTRAST:g}, where the solver's "
                "sub-panels no longer follow its transmission lobe (bounds of 20 % and more, negative values)")
    return None


def check_adding_doubling(model) -> None:
    """ValueError unless ``model`` is a stack this method tabulates (``adding_doubling_gap``)."""
    gap = adding_doubling_gap(model)
    if gap is not None:
        raise ValueError(f"method 'adding-doubling' cannot tabulate this model: {gap} (use method 'pfmc')")


def solver_settings(nodes: int | None = None, orders: int | None = None) -> dict:
    """The solver settings a table is requested with (part of its cache key: a change of
    the defaults makes new tables): ``TABLE_NODES`` and automatic orders unless given.
    The solve may raise the nodes (``nodes_for_g``); ``meta["solver"]`` records what it used."""
    settings = Settings(nodes=TABLE_NODES if nodes is None else nodes, orders=orders, film_lookup=True)
    return {**settings.to_dict(), "table_settings": TABLE_RULES}


def tabulate_adding_doubling(model, grid: TableGrid, rel_error: float = DEFAULT_REL_ERROR, wavelengths=None,
                             nodes: int | None = None, orders: int | None = None,
                             solver: dict | None = None) -> TableData:
    """The table of a ``Layered`` stack on ``grid`` by adding-doubling (module
    docstring). ``rel_error`` sets the solver's truncations (``table_settings``) and is
    recorded as the target; ``meta["error_bound_max_rel"]`` is what the solver's bound
    achieved over the significant cells. ``nodes`` (default ``TABLE_NODES``) and ``orders``
    (default automatic): the solver's accuracy settings. ``solver``: keyword arguments of
    ``bsdflab.solvers.solve`` that replace ``table_settings``'s (e.g. a reference table)."""
    check_adding_doubling(model)
    names, model_wl, P, lum_w = table_channels(wavelengths)
    start = time.perf_counter()
    lobes = TWO_SIDED_LOBES if _transmits(model) else LOBES[:1]
    wi, wo = lobe_directions(grid, len(lobes))
    thicknesses = list(grid.thickness_nm) or [-1.0]
    values, bounds, lookup_error, orders_used, first = [], [], None, 0, None
    for t in thicknesses:
        model_t = with_film_thickness(model, t)
        if first is not None and hasattr(model.interfaces[0], "alpha"):  # rough top: reuse the rest
            sol = first.with_model(model_t)
        else:
            sol = first = solve(model_t, model_wl, nodes=TABLE_NODES if nodes is None else nodes,
                                orders=orders, film_lookup=True,
                                **{**table_settings(rel_error, len(model_wl)), **(solver or {})})
        v, e = sol.eval_with_error(wi, wo, scattered_only=True)
        values.append(v / np.abs(wo[:, 2:]) @ P.T)
        bounds.append(e / np.abs(wo[:, 2:]) @ np.abs(P).T)
        orders_used = max(orders_used, sol.orders)
        if sol.film_lookup_error is not None:
            lookup_error = max(lookup_error or 0.0, sol.film_lookup_error)
    shape = (len(lobes), len(thicknesses), grid.n_theta_i, grid.n_theta_o, grid.n_phi, len(names))
    # The statistics are of the stored (float32) cells, so a table assembled from units
    # (bsdflab.tables.units) reports the same ones. Per thickness the rows run lobe-major.
    by_node = (len(thicknesses), len(lobes), *shape[2:])
    vals = np.stack(values).reshape(by_node).swapaxes(0, 1).astype(np.float32)
    errs = np.stack(bounds).reshape(by_node).swapaxes(0, 1).astype(np.float32)
    meta = {"bsdflab_version": __version__, "method": METHOD,
            "solver": {**sol.settings.to_dict(), "orders": orders_used},
            "seconds": round(time.perf_counter() - start, 3), "threads": _core.worker_count(),
            "error_kind": "deterministic bound (adding-doubling, Solution.eval_with_error)",
            "film_lookup_error": lookup_error,
            **bound_statistics(vals.astype(np.float64), errs.astype(np.float64), lum_w)}
    table = TableData(model=model.to_dict(), grid=grid, lobes=lobes, channels=names, split_direct=True,
                      values=vals, stderr=errs,
                      samples=np.ones(shape[:-1], dtype=np.int32), rel_error_target=float(rel_error), meta=meta)
    table.check()
    return table


def bound_statistics(values: np.ndarray, bounds: np.ndarray, lum_w: np.ndarray) -> dict:
    """The error bound relative to the luminance over the significant cells (luminance >
    ``SIGNIFICANT`` x the max): its max, RMS and 95th percentile, as ``meta`` keys; and
    the same per part (``rel_error_by_part``, a part's cells against its own max)."""
    lum, lum_err = values @ lum_w, bounds @ np.abs(lum_w)
    return {**_bound_figures(lum.ravel(), lum_err.ravel()),
            "rel_error_by_part": by_part(LOBES_BY_COUNT[values.shape[0]], lum.ravel(), lum_err.ravel(),
                                         lambda a, b: {k: v for k, v in _bound_figures(a, b).items()
                                                       if k.startswith("rel_error")})}


def _bound_figures(lum: np.ndarray, lum_err: np.ndarray) -> dict:
    mask = lum > SIGNIFICANT * max(float(lum.max()), 1e-300)
    rel = lum_err[mask] / lum[mask] if np.any(mask) else np.zeros(1)
    rms, top = float(np.sqrt(np.mean(rel**2))), float(rel.max())
    return {"error_bound_max_rel": top, "error_bound_rms_rel": rms, "rel_error_rms": rms,
            "rel_error_p95": float(np.percentile(rel, 95)), "rel_error_max": top}


def lobe_directions(grid: TableGrid, n_lobes: int) -> tuple[np.ndarray, np.ndarray]:
    """(wi, wo), each (n_lobes x theta_i x theta_o x phi, 3), lobe-major: the cells'
    directions as the core's TableGrid::cell_directions gives them (lobes 2 and 3 lit
    from below; wo above for lobes 0 and 3)."""
    ti, to, ph = np.meshgrid(grid.theta_i, grid.theta_o, grid.phi, indexing="ij")
    wi = np.stack([np.sin(ti), np.zeros_like(ti), np.cos(ti)], axis=-1).reshape(-1, 3)
    wo = np.stack([np.sin(to) * np.cos(ph), np.sin(to) * np.sin(ph), np.cos(to)], axis=-1).reshape(-1, 3)
    flip = np.array([1.0, 1.0, -1.0])
    pairs = [(wi, wo), (wi, wo * flip), (wi * flip, wo * flip), (wi * flip, wo)][:n_lobes]
    return np.concatenate([a for a, _ in pairs]), np.concatenate([b for _, b in pairs])


def _transmits(model: Layered) -> bool:
    from bsdflab.lobes import Lobe

    return bool(model.lobes & Lobe.TRANSMISSION)
