"""The measured coverage of PFMC table errors: how often a cell's |value - truth| exceeded
k of its stated standard errors, against the normal 2 (1 - Phi(k)).

Measured by ``python bench/coverage_tables.py --what tables`` (docs/coverage.md): 200 seeds
of a 3 x 4 x 3 x 2-thickness table (450/550/650 nm, rel_error 0.05, min_samples 512), one
channel per cell (72 independent cells a seed, 14 400 in all), the truth an adding-doubling
table (error bound <= 0.4 % relative, in the denominator). The figures hold for the
estimator version they were measured with; a table of another version reports none.
"""
from __future__ import annotations

from typing import Any

MEASURED_VERSION = 7
COMMAND = "python bench/coverage_tables.py --what tables --seeds 200"
# per stack: the share of cells beyond k = 2, 3, 4 standard errors (pfmc2; pfmc alike)
NORMAL = {"2": 0.0455, "3": 0.0027, "4": 0.000063}
MEASURED = {
    "snake (xenopeltis)": {"2": 0.0469, "3": 0.0033, "4": 0.00028},
    "plastic (smooth top, scattering slab, diffuse)": {"2": 0.0494, "3": 0.0029, "4": 0.00007},
}


def coverage_record(estimator_version: Any) -> dict[str, Any] | None:
    """What ``TableData.accuracy()`` reports as ``coverage`` for a PFMC table of this
    estimator version: the measured shares beyond k sigma, the normal ones, the units and the
    command; None when the version's coverage was not measured."""
    if isinstance(estimator_version, bool) or estimator_version != MEASURED_VERSION:
        return None
    return {"beyond_k_sigma": {name: dict(v) for name, v in MEASURED.items()}, "normal": dict(NORMAL),
            "cells": 14400, "method": "200 seeds x 72 cells vs adding-doubling, one channel per cell",
            "command": COMMAND, "doc": "docs/coverage.md"}
