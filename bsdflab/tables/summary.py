"""Numbers that describe a table's accuracy, and the one definition of "target met".
(Functions of a ``TableData``, which reads this module for ``accuracy()``: no import back.)

**Target met** (used by ``TableData.accuracy``, `bsdflab tabulate`, `bsdflab table info`,
renders and jobs): the 95th percentile, over the table's significant cells (luminance
above 1 % of the table's maximum), of each cell's relative error of luminance is at most
the target (``rel_error_target``). A cell's error is its standard error for a PFMC
table and the solver's deterministic bound for an adding-doubling one. The max is
always reported beside it: up to 5 % of the significant cells may exceed the target.

The statistics are those the tabulator recorded in the file's meta (``rel_error_p95``,
``rel_error_max``, ``rel_error_rms``): a PFMC table's luminance error comes from the walks
themselves, which the stored per-channel errors only bound. Files without them get the
statistics of the stored errors (``relative_error_summary``).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab.tables.channels import LUMINANCE_RGB
from bsdflab.tables.coverage import coverage_record

SIGNIFICANT = 0.01  # cells below 1 % of the table's maximum are left out of error statistics
TARGET_PERCENTILE = 95
BOUND = "deterministic bound"
STDERR = "standard error"
EXACT = "none (one exact evaluation per cell)"


def luminance_weights(table) -> np.ndarray:
    """Rec. 709 weights for RGB tables, the channel mean for spectral ones (as the tabulator
    uses to decide when a cell is converged)."""
    if not table.spectral:
        return LUMINANCE_RGB
    return np.full(len(table.channels), 1.0 / len(table.channels))


def relative_error_summary(table) -> dict[str, float]:
    """RMS, 95th percentile and max relative error (the stored ``stderr``: standard error
    or bound) of the luminance over the cells whose luminance exceeds 1 % of the table's
    maximum, and how many cells that is.

    The luminance error adds the channels' errors (an upper bound: channels share walks).
    """
    lum = luminance_weights(table)
    y = table.values.astype(np.float64) @ lum
    e = table.stderr.astype(np.float64) @ np.abs(lum)
    mask = y > SIGNIFICANT * max(float(y.max(initial=0.0)), 1e-300)
    if not np.any(mask):
        return {"rms": 0.0, "p95": 0.0, "max": 0.0, "cells": 0}
    r = e[mask] / y[mask]
    return {"rms": float(np.sqrt(np.mean(r**2))), "p95": float(np.percentile(r, TARGET_PERCENTILE)),
            "max": float(r.max()), "cells": int(mask.sum())}


def error_kind(table) -> str:
    """What a cell's stored error is: a deterministic bound, a standard error, or none."""
    if table.meta.get("method") == "adding-doubling":
        return BOUND
    return STDERR if table.split_direct or np.any(table.stderr > 0) else EXACT


def achieved(table) -> dict[str, Any]:
    """RMS, 95th percentile and max relative error of the significant cells (module
    docstring: the tabulator's own figures where the file records them), the cell count
    and the error's kind."""
    stored = relative_error_summary(table)
    kind = error_kind(table)
    if kind == EXACT:
        return {"rms": 0.0, "p95": 0.0, "max": 0.0, "cells": stored["cells"], "kind": kind}
    meta = table.meta
    names = {"rms": "rel_error_rms", "p95": "rel_error_p95", "max": "rel_error_max"}
    if all(isinstance(meta.get(k), (int, float)) for k in names.values()):
        return {**{k: float(meta[v]) for k, v in names.items()}, "cells": stored["cells"], "kind": kind}
    return {**stored, "kind": kind}


def accuracy(table) -> dict[str, Any]:
    """``target_met`` (module docstring), the statistics it rests on (``p95``, ``max``,
    ``rms``, ``cells``, ``kind``), PFMC's ``capped_cells`` (stopped at ``max_samples``) and
    ``advice``: what would meet the target (None when met)."""
    a = achieved(table)
    target = table.rel_error_target
    met = a["p95"] <= target
    cap = table.meta.get("max_samples") if a["kind"] == STDERR else None
    capped = int(np.count_nonzero(table.samples >= cap)) if isinstance(cap, int) and not isinstance(cap, bool) else 0
    advice = None
    if not met:
        what = f"the {TARGET_PERCENTILE}th percentile of the cells' relative {a['kind']}, {a['p95']:.4g}, " \
               f"exceeds the target {target:g}"
        if a["kind"] == BOUND:
            nodes = table.meta.get("solver", {}).get("nodes")
            advice = f"{what}: raise --nodes (this table used {nodes}) or --orders"
        elif capped:
            advice = f"{what}: raise --max-samples ({capped} cells stopped at {cap})"
        else:
            advice = f"{what}: raise --min-samples (a longer pilot sets each cell's effort more surely)"
    return {"target_met": bool(met), **a, "capped_cells": capped, "max_samples": cap, "advice": advice}


def describe_accuracy(table) -> tuple[dict[str, Any], list[tuple[str, str]]]:
    """(``accuracy(table)``, labelled lines for the command line) in the words of the
    module docstring: the target, what was achieved, and whether the target was met."""
    a = accuracy(table)
    target = table.rel_error_target
    noun, note = ("error", " (none: each cell is one exact evaluation)") if a["kind"] == EXACT else (a["kind"], "")
    lines = [
        ("target", f"{target:g}: the {TARGET_PERCENTILE}th percentile of each cell's relative {noun} of "
                   f"luminance, over the {a['cells']} cells above 1 % of the table max{note}"),
        ("achieved", f"{TARGET_PERCENTILE}th pct {a['p95']:.4g}  max {a['max']:.4g}  RMS {a['rms']:.4g}"),
        ("target met", ("yes" if a["target_met"] else "NO")
         + f": {TARGET_PERCENTILE}th pct {a['p95']:.4g} {'<=' if a['target_met'] else '>'} {target:g} "
           f"(max {a['max']:.4g})"),
    ]
    if a["kind"] == STDERR:
        lines.append(("capped cells", f"{a['capped_cells']} of {table.samples.size} stopped at max_samples "
                                      f"{a['max_samples']}"))
        cov = coverage_record(table.meta.get("estimator_version"), table.meta.get("min_samples"))
        if cov is not None and not cov["applies"]:
            lines.append(("error coverage", cov["warning"]))
    return a, lines
