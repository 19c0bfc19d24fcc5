"""Input checks run before any C++: each raises ValueError naming the parameter and range."""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab.util import ranges

# Directions must be unit vectors to this tolerance (float32 inputs normalised by callers
# are accepted; anything further off is a caller's bug, not rounding).
UNIT_TOLERANCE = 1e-4

# Physical ranges (docs/limits.md), written once in bsdflab/util/ranges.py (the service reads
# them there too); named here as well for the checks' callers (check.MAX_IOR, ...).
MIN_IOR, MAX_IOR, MAX_EXTINCTION = ranges.MIN_IOR, ranges.MAX_IOR, ranges.MAX_EXTINCTION
MIN_WAVELENGTH_NM, MAX_WAVELENGTH_NM = ranges.MIN_WAVELENGTH_NM, ranges.MAX_WAVELENGTH_NM
MAX_FILM_THICKNESS_NM = ranges.MAX_FILM_THICKNESS_NM

# Seeds are the core's uint64; counts of work (walks, depths) its int32 and far below.
MAX_SEED = (1 << 64) - 1
MAX_COUNT = 1 << 24
_NUMBER_ERRORS = (TypeError, ValueError, OverflowError)


def real_scalar(name: str, value: Any, lo: float | None = None, hi: float | None = None,
                lo_open: bool = False, hi_open: bool = False) -> float:
    """A finite real number in [lo, hi] (or open ends when asked)."""
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be a real number, got {brief(value)}")
    try:
        v = float(value)
    except OverflowError:
        raise ValueError(f"{name} must be finite, got {brief(value)}") from None
    except _NUMBER_ERRORS:
        raise ValueError(f"{name} must be a real number, got {brief(value)}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    _check_range(name, np.array([v]), lo, hi, lo_open, hi_open)
    return v


def real_array(name: str, value: Any, lo: float | None = None, hi: float | None = None,
               lo_open: bool = False, hi_open: bool = False, ndim: int | None = None) -> np.ndarray:
    """A finite float64 array with every entry in the given range."""
    a = _float_array(name, value, "an array of real numbers")
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
    a = _float_array(name, value, "an array of shape (N, 3)")
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3) or (3,), got {np.shape(value)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite (found NaN or infinity)")
    with np.errstate(over="ignore"):  # huge entries: an infinite length, refused below
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
    if isinstance(value, (str, bytes, float, np.floating)):
        raise ValueError(f"lobes must be a Lobe flag, got {brief(value)}")
    try:
        v = int(value)
    except _NUMBER_ERRORS:
        raise ValueError(f"lobes must be a Lobe flag, got {brief(value)}") from None
    if v < 0 or v > 63:
        raise ValueError(f"lobes must be a combination of Lobe flags (0..63), got {brief(v)}")
    return v


def seed(value: Any, name: str = "seed") -> int:
    return integer(name, value, 0, MAX_SEED)


def integer(name: str, value: Any, lo: int, hi: int | None = None) -> int:
    """An int (or numpy integer; not a bool) in [lo, hi] (``hi`` None: no upper bound).

    The one integer check of the package: every message reads "NAME must be an integer in
    [LO, HI], got VALUE" (or "... an integer >= LO, got VALUE")."""
    if (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo
            or (hi is not None and value > hi)):
        bounds = f"in [{lo}, {hi}]" if hi is not None else f">= {lo}"
        raise ValueError(f"{name} must be an integer {bounds}, got {brief(value)}")
    return int(value)


def flag(name: str, value: Any) -> bool:
    """A boolean: True or False (numpy bools too); not 0/1, strings or other truthy things.
    The one flag check of the package ("NAME must be true or false, got VALUE")."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be true or false, got {brief(value)}")
    return bool(value)


def count(name: str, value: Any, hi: int = MAX_COUNT) -> int:
    """A positive amount of work (walks, depth): an integer in [1, hi]."""
    return integer(name, value, 1, hi)


def ior(name: str, value: Any) -> float:
    """A real refractive index in [MIN_IOR, MAX_IOR]."""
    return real_scalar(name, value, MIN_IOR, MAX_IOR)


def wavelengths_nm(name: str, value: Any) -> np.ndarray:
    """Vacuum wavelengths in nm within [MIN_WAVELENGTH_NM, MAX_WAVELENGTH_NM]."""
    return real_array(name, value, MIN_WAVELENGTH_NM, MAX_WAVELENGTH_NM)


def film_thickness(name: str, value: Any, array: bool = False, ndim: int | None = None):
    """Film thickness(es) in nm within [0, MAX_FILM_THICKNESS_NM] (an array of `ndim`
    dimensions if given)."""
    if array:
        return real_array(name, value, 0.0, MAX_FILM_THICKNESS_NM, ndim=ndim)
    return real_scalar(name, value, 0.0, MAX_FILM_THICKNESS_NM)


def _float_array(name: str, value: Any, what: str) -> np.ndarray:
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be {what}, got {brief(value)}")
    try:
        return np.asarray(value, dtype=np.float64)
    except OverflowError:
        raise ValueError(f"{name} must be finite (an integer too large for a float)") from None
    except _NUMBER_ERRORS:
        raise ValueError(f"{name} must be {what}") from None


def one_line(text: str, limit: int = 200) -> str:
    """A message squeezed to one line of at most ``limit`` characters."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


def brief(value: Any, limit: int = 60) -> str:
    """repr(value) cut to one short line (huge or nested inputs stay readable)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 64:
        return f"an integer of {value.bit_length()} bits"
    try:
        text = repr(value)
    except Exception:  # a hostile __repr__ must not replace the real error
        text = f"<{type(value).__name__}>"
    return one_line(text, limit)


def per_row(name: str, value: Any, n: int, lo: float | None = None,
            hi: float | None = None) -> np.ndarray | None:
    """None, a number, or one value per row: a float64 array of shape (n,) or None."""
    if value is None:
        return None
    a = real_array(name, value, lo, hi)
    if a.ndim == 0:
        return np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"{name} must be a number or have shape ({n},), got {a.shape}")
    return np.ascontiguousarray(a)


MAX_NESTING = 64  # dicts and lists inside each other in a request (a scene needs ~8)


def nesting(name: str, value: Any, limit: int = MAX_NESTING) -> None:
    """Refuse JSON-like data nested more than ``limit`` levels deep (checked without
    recursion, so hostile depth cannot exhaust the stack)."""
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict):
            children = item.values()
        elif isinstance(item, (list, tuple)):
            children = item
        else:
            continue
        if depth > limit:
            raise ValueError(f"{name} is nested more than {limit} levels deep")
        stack.extend((child, depth + 1) for child in children)
