"""Tiny units for measuring the cluster itself (bench/bench_distributed.py): per-unit
overhead and result transfer, with no bsdflab work inside."""
from __future__ import annotations

import numpy as np


def noop_unit(unit: int) -> int:
    return unit


def payload_unit(nbytes: int, unit: int) -> np.ndarray:
    """A result of ``nbytes`` bytes (the transfer cost of a unit's result)."""
    return np.full(max(1, nbytes // 8), float(unit))
