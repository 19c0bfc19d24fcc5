"""Job kind "tabulate": measure a model into a table file in the table cache.

Request (normalised)::

    {"model": <BSDF dict>, "grid": {"n_theta_i", "n_theta_o", "n_phi", "thickness_nm"},
     "rel_error": 0.01, "wavelengths": null | [nm, ...], "min_samples": 512,
     "max_samples": 65536, "seed": 0, "method": "pfmc" | "adding-doubling"}

``method`` "adding-doubling" (a reflecting ``Layered`` model) solves the table
deterministically (bsdflab.tables.adding_doubling); the walk settings do not apply to it
and its cache key holds the method and the solver's settings instead.

``out_dir`` is a table cache folder (``bsdflab.tables.cache``): the table is
``out_dir/<key>.exr`` with the cache's own key, so the same table asked for by a render's
``"tabulated"`` material (with that folder as its cache) is the same file.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from bsdflab.bsdfs import from_dict
from bsdflab.requests import model_from_spec
from bsdflab.tables import TableGrid, cache_key, cached_table, read_attributes, read_table, tabulate
from bsdflab.tables.adding_doubling import check_adding_doubling
from bsdflab.tables.channels import table_channels
from bsdflab.tables.file_format import HASH_ATTRIBUTE
from bsdflab.tables.summary import relative_error_summary
from bsdflab.tables.tabulate import DEFAULT_MAX_SAMPLES, DEFAULT_MIN_SAMPLES, METHODS
from bsdflab.util import args as check
from bsdflab.util.progress import monitored

FIELDS = {"model", "preset", "overrides", "grid", "rel_error", "wavelengths", "min_samples",
          "max_samples", "seed", "method"}


def normalise(request: dict[str, Any]) -> dict[str, Any]:
    unknown = set(request) - FIELDS
    if unknown:
        raise ValueError(f"unknown tabulate request fields: {', '.join(sorted(unknown))}")
    model = model_from_spec(request)
    grid_spec = request.get("grid") or {}
    if not isinstance(grid_spec, dict):
        raise ValueError("grid must be a dict with n_theta_i, n_theta_o, n_phi, thickness_nm")
    defaults = TableGrid().to_dict()
    unknown = set(grid_spec) - set(defaults)
    if unknown:
        raise ValueError(f"unknown grid fields: {', '.join(sorted(unknown))}")
    grid = TableGrid.from_dict({**defaults, **grid_spec})
    wavelengths = request.get("wavelengths")
    if wavelengths is not None:
        wavelengths = [float(w) for w in table_channels(wavelengths)[1]]
    min_samples = check.count("min_samples", request.get("min_samples", DEFAULT_MIN_SAMPLES))
    max_samples = check.count("max_samples", request.get("max_samples", DEFAULT_MAX_SAMPLES))
    if max_samples < min_samples:
        raise ValueError(f"max_samples ({max_samples}) must be >= min_samples ({min_samples})")
    method = request.get("method", "pfmc")
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {check.brief(method)}")
    if method == "adding-doubling":
        check_adding_doubling(model)   # refused at submission, not when the job runs
    _check_spectral(model, wavelengths)
    return {"model": model.to_dict(), "grid": grid.to_dict(), "method": method,
            "rel_error": check.real_scalar("rel_error", request.get("rel_error", 0.01), 0.0, 1.0, lo_open=True),
            "wavelengths": wavelengths, "min_samples": min_samples, "max_samples": max_samples,
            "seed": check.seed(request.get("seed", 0))}


def _check_spectral(model, wavelengths) -> None:
    """A table asks its model at spectral wavelengths (``table_channels``); a model that
    answers in RGB only (a MERL file, an RGB RGL file) is refused here, at submission,
    rather than failing in the worker."""
    model_wl = table_channels(wavelengths)[1]
    try:
        answered = len(model._channels(np.asarray(model_wl, dtype=float))[0])
    except ValueError:
        answered = -1
    if answered != len(model_wl):
        raise ValueError(f"a {model.type_name} model of this file answers in RGB only, and tables are made "
                         "from spectra: tabulate a spectral file (an RGL file with wavelengths)")


def cells(request: dict[str, Any]) -> int:
    """Table cells the request asks for (both lobes counted), for request caps."""
    g = request["grid"]
    return 2 * max(1, len(g["thickness_nm"])) * g["n_theta_i"] * g["n_theta_o"] * g["n_phi"]


def _key_arguments(request: dict[str, Any]):
    """(model, grid, rel_error, channels) and the effort and seed, as the cache keys them
    (defaults spelled out share the entry of requests that leave them out)."""
    names = table_channels(request["wavelengths"])[0]
    effort = {"min_samples": request["min_samples"], "max_samples": request["max_samples"],
              "seed": request["seed"], "method": request.get("method", "pfmc")}
    return request["model"], TableGrid.from_dict(request["grid"]), request["rel_error"], names, effort


def key(request: dict[str, Any]) -> str:
    """The table cache's key (``bsdflab.tables.cache_key``) of this request."""
    model, grid, rel_error, names, effort = _key_arguments(request)
    return cache_key(model, grid, rel_error, names, **effort)


def existing(request: dict[str, Any], out_dir: Path) -> dict[str, Any] | None:
    path = Path(out_dir) / f"{key(request)}.exr"
    if not path.is_file():
        return None
    try:
        return {"hash": path.stem, "files": {"exr": path.name}, "from_cache": True, **describe(path)}
    except ValueError:   # damaged: the job rebuilds it (cached_table does)
        return None


def run(request: dict[str, Any], out_dir: Path, progress, cancelled, runner=None) -> dict[str, Any]:
    model_dict, grid, rel_error, names, effort = _key_arguments(request)
    model = from_dict(model_dict)

    def make():
        with monitored(lambda stage, fraction: progress(fraction), cancelled):
            return tabulate(model, grid, rel_error=rel_error, wavelengths=request["wavelengths"],
                            min_samples=request["min_samples"], max_samples=request["max_samples"],
                            seed=request["seed"], progress=False, runner=runner, method=effort["method"])

    table, path, hit = cached_table(model_dict, grid, rel_error, names, make, directory=out_dir, **effort)
    if path is None:
        raise OSError(f"could not write the table into {out_dir}")
    return {"hash": path.stem, "files": {"exr": path.name}, "from_cache": hit, **describe(path, table)}


def describe(path: str | os.PathLike, table=None) -> dict[str, Any]:
    """What a table file holds: model, grid, lobes, channels, effort and error statistics."""
    table = read_table(path) if table is None else table
    samples = np.asarray(table.samples)
    return {"model": table.model, "grid": table.grid.to_dict(), "lobes": list(table.lobes),
            "channels": list(table.channels), "split_direct": bool(table.split_direct),
            "rel_error_target": float(table.rel_error_target), "meta": table.meta,
            "error": relative_error_summary(table),
            "samples": {"total": int(samples.sum()), "min": int(samples.min()),
                        "max": int(samples.max()), "mean": float(samples.mean())},
            "content_hash": read_attributes(path).get(HASH_ATTRIBUTE, ""),
            "bytes": os.path.getsize(path)}
