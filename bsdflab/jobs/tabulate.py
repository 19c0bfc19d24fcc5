"""Job kind "tabulate": measure a model into a table file in the table cache.

Request: a ``TableRequest`` dict (bsdflab.tables.request), normalised to ``TableRequest.to_dict``::

    {"model": <BSDF dict>, "grid": {"n_theta_i", "n_theta_o", "n_phi", "thickness_nm"},
     "rel_error": 0.01, "wavelengths": null | [nm, ...], "method": "pfmc" | "adding-doubling",
     "min_samples": 512, "max_samples": 65536, "seed": 0[, "nodes": ..., "orders": ...]}

A request may give ``preset`` and ``overrides`` instead of ``model``, and ``method``
"auto" (the default): adding-doubling wherever the solver covers the model, else PFMC;
the normalised request holds the method chosen, and the result says why
(``method_note``).

``out_dir`` is a table cache folder (``bsdflab.tables.cache``): the table is
``out_dir/<key>.exr`` with the request's own key, so the same table asked for by a
render's ``"tabulated"`` material (with that folder as its cache) is the same file.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from bsdflab.requests import model_from_spec
from bsdflab.tables import TableRequest, get, read_attributes, read_table
from bsdflab.tables.channels import table_channels
from bsdflab.tables.file_format import HASH_ATTRIBUTE
from bsdflab.tables.summary import accuracy
from bsdflab.tables.tabulate import make_table
from bsdflab.util.progress import monitored

SPEC = ("model", "preset", "overrides")  # the model's request form (bsdflab.requests)


def normalise(request: dict[str, Any]) -> dict[str, Any]:
    """The request validated (ValueError naming the field) with its method chosen."""
    return _normalised(_checked(request))


def _checked(request: dict[str, Any]) -> TableRequest:
    if not isinstance(request, dict):
        raise ValueError(f"a tabulate request must be a dict, got {type(request).__name__}")
    rest = {k: v for k, v in request.items() if k not in SPEC}
    model = model_from_spec({k: v for k, v in request.items() if k in SPEC})
    table_request = TableRequest.from_dict(rest, model=model)
    _check_spectral(model, table_request.wavelengths)
    return table_request


def _normalised(request: TableRequest) -> dict[str, Any]:
    return {**request.to_dict(), "method_note": request.method_note}


def _request(normalised: dict[str, Any]) -> TableRequest:
    return TableRequest.from_dict({k: v for k, v in normalised.items() if k != "method_note"})


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
    """Table cells the request asks for (a transmissive model's four parts counted: an
    upper bound before the model is asked), for request caps."""
    return _request(request).cells()


def key(request: dict[str, Any]) -> str:
    """The table cache's key (``TableRequest.key``) of this normalised request."""
    return _request(request).key()


def prepared(request: dict[str, Any], out_dir: Path) -> dict[str, Any]:
    """``normalise``, ``key``, ``cells`` and ``existing`` with the model built once (each
    builds it: a model naming a measured file read that file each time), for a service's
    check worker: ``{"request", "key", "cells", "existing"}``."""
    table_request = _checked(request)
    normalised, k = _normalised(table_request), table_request.key()
    return {"request": normalised, "key": k, "cells": table_request.cells(),
            "existing": _existing(Path(out_dir) / f"{k}.exr", normalised)}


def existing(request: dict[str, Any], out_dir: Path) -> dict[str, Any] | None:
    return _existing(Path(out_dir) / f"{key(request)}.exr", request)


def _existing(path: Path, request: dict[str, Any]) -> dict[str, Any] | None:
    if not path.is_file():
        return None
    try:
        return {"hash": path.stem, "files": {"exr": path.name}, "from_cache": True,
                "method_note": request.get("method_note"), **describe(path)}
    except ValueError:   # damaged: the job rebuilds it (the cache does)
        return None


def run(request: dict[str, Any], out_dir: Path, progress, cancelled, runner=None) -> dict[str, Any]:
    req = _request(request)

    def make():
        with monitored(lambda stage, fraction: progress(fraction), cancelled):
            return make_table(req, progress=False, runner=runner)

    table, path, hit = get(req, cache=out_dir, make=make)
    if path is None:
        raise OSError(f"could not write the table into {out_dir}")
    return {"hash": path.stem, "files": {"exr": path.name}, "from_cache": hit,
            "method_note": request.get("method_note"), **describe(path, table)}


def describe(path: str | os.PathLike, table=None) -> dict[str, Any]:
    """What a table file holds: model, grid, lobes, channels, effort and error statistics
    (``error``: the figures "target met" is decided by, bsdflab.tables.summary)."""
    table = read_table(path) if table is None else table
    samples = np.asarray(table.samples)
    a = accuracy(table)
    return {"model": table.model, "grid": table.grid.to_dict(), "lobes": list(table.lobes),
            "channels": list(table.channels), "split_direct": bool(table.split_direct),
            "rel_error_target": float(table.rel_error_target), "meta": table.meta,
            "method": table.meta.get("method", "pfmc"),
            "error": {k: a[k] for k in ("rms", "p95", "max", "cells")},
            "error_kind": a["kind"], "target_met": a["target_met"],
            "samples": {"total": int(samples.sum()), "min": int(samples.min()),
                        "max": int(samples.max()), "mean": float(samples.mean())},
            "content_hash": read_attributes(path).get(HASH_ATTRIBUTE, ""),
            "bytes": os.path.getsize(path)}
