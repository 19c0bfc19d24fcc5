"""Input checks run before any C++: each raises ValueError naming the parameter and range."""
from __future__ import annotations

from typing import Any

import numpy as np

# Directions must be unit vectors to this tolerance (float32 inputs normalised by callers
# are accepted; anything further off is a caller's bug, not rounding).
UNIT_TOLERANCE = 1e-4


def real_scalar(name: str, value: Any, lo: float | None = None, hi: float | None = None,
                lo_open: bool = False, hi_open: bool = False) -> float:
    """A finite real number in [lo, hi] (or open ends when asked)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    _check_range(name, np.array([v]), lo, hi, lo_open, hi_open)
    return v


def real_array(name: str, value: Any, lo: float | None = None, hi: float | None = None,
               lo_open: bool = False, hi_open: bool = False, ndim: int | None = None) -> np.ndarray:
    """A finite float64 array with every entry in the given range."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an array of real numbers") from None
    if ndim is not None and a.ndim != ndim:
        raise ValueError(f"{name} must be {ndim}-dimensional, got shape {a.shape}")
    if a.size == 0:
        raise ValueError(f"{name} must not be empty")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite (found NaN or infinity)")
    _check_range(name, a, lo, hi, lo_open, hi_open)
    return a


def _check_range(name, a, lo, hi, lo_open, hi_open):
    if lo is not None and (np.any(a <= lo) if lo_open else np.any(a < lo)):
        raise ValueError(f"{name} must be {'>' if lo_open else '>='} {lo}; got min {a.min():g}")
    if hi is not None and (np.any(a >= hi) if hi_open else np.any(a > hi)):
        raise ValueError(f"{name} must be {'<' if hi_open else '<='} {hi}; got max {a.max():g}")


def directions(name: str, value: Any) -> np.ndarray:
    """Unit direction vectors as a C-contiguous float64 array of shape (N, 3).

    A single direction of shape (3,) is promoted to (1, 3).
    """
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an array of shape (N, 3)") from None
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3) or (3,), got {np.shape(value)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite (found NaN or infinity)")
    length = np.linalg.norm(a, axis=1)
    bad = np.abs(length - 1.0) > UNIT_TOLERANCE
    if np.any(bad):
        raise ValueError(f"{name} must be unit vectors (|w| = 1 within {UNIT_TOLERANCE}); "
                         f"row {int(np.argmax(bad))} has length {length[bad][0]:.6g}")
    return np.ascontiguousarray(a)


def direction_pair(wi: Any, wo: Any) -> tuple[np.ndarray, np.ndarray]:
    """wi and wo broadcast against each other to a common (N, 3)."""
    a, b = directions("wi", wi), directions("wo", wo)
    if len(a) != len(b):
        if len(a) == 1:
            a = np.repeat(a, len(b), axis=0)
        elif len(b) == 1:
            b = np.repeat(b, len(a), axis=0)
        else:
            raise ValueError(f"wi and wo must have the same length or one of them length 1; "
                             f"got {len(a)} and {len(b)}")
    return a, b


def uniforms(name: str, value: Any, shape: tuple[int, ...]) -> np.ndarray:
    """Random numbers in [0, 1] of an exact shape."""
    a = real_array(name, value, 0.0, 1.0)
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    return np.ascontiguousarray(a)


def lobe_mask(value: Any) -> int:
    try:
        v = int(value)
    except (TypeError, ValueError):
        raise ValueError(f"lobes must be a Lobe flag, got {value!r}") from None
    if v < 0 or v > 63:
        raise ValueError(f"lobes must be a combination of Lobe flags (0..63), got {v}")
    return v


def seed(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"seed must be a non-negative integer, got {value!r}")
    return int(value)


def per_row(name: str, value: Any, n: int, lo: float | None = None) -> np.ndarray | None:
    """None, a number, or one value per row: a float64 array of shape (n,) or None."""
    if value is None:
        return None
    a = real_array(name, value, lo)
    if a.ndim == 0:
        return np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"{name} must be a number or have shape ({n},), got {a.shape}")
    return np.ascontiguousarray(a)
