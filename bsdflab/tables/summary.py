"""Numbers that describe a table's accuracy, computed from the stored data alone."""
from __future__ import annotations

import numpy as np

from bsdflab.tables.channels import LUMINANCE_RGB
from bsdflab.tables.data import TableData

SIGNIFICANT = 0.01  # cells below 1 % of the table's maximum are left out of error statistics


def luminance_weights(table: TableData) -> np.ndarray:
    """Rec. 709 weights for RGB tables, the channel mean for spectral ones (as the tabulator
    uses to decide when a cell is converged)."""
    if not table.spectral:
        return LUMINANCE_RGB
    return np.full(len(table.channels), 1.0 / len(table.channels))


def relative_error_summary(table: TableData) -> dict[str, float]:
    """RMS, 95th percentile and max relative standard error of the luminance over the cells
    whose luminance exceeds 1 % of the table's maximum, and how many cells that is.

    The luminance error adds the channels' errors (an upper bound: channels share walks).
    """
    lum = luminance_weights(table)
    y = table.values.astype(np.float64) @ lum
    e = table.stderr.astype(np.float64) @ np.abs(lum)
    mask = y > SIGNIFICANT * max(float(y.max(initial=0.0)), 1e-300)
    if not np.any(mask):
        return {"rms": 0.0, "p95": 0.0, "max": 0.0, "cells": 0}
    r = e[mask] / y[mask]
    return {"rms": float(np.sqrt(np.mean(r**2))), "p95": float(np.percentile(r, 95)),
            "max": float(r.max()), "cells": int(mask.sum())}
