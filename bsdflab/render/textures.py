"""Procedural hexagonal snake scales over a surface's (u, v).

The geometry, hashes and shading (dome, tilt, film-thickness factor) are documented once, in
``core/include/bsdflab/scale_texture.h``; this module validates parameters, serialises them
and vectorises lookups. In short: rows of scales are rings around the body at
``u = i / scales_per_unit_u``, each holding ``scales_around`` scales over v in [0, 1); odd
rows are shifted by half a spacing; centres are jittered per scale; a point belongs to the
nearest centre, and lies in a gap when it is closer than ``gap / 2`` spacings to its cell's
boundary.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.util import args as check

MAX_SCALES_AROUND = 1 << 20
MAX_SEED = (1 << 64) - 1


def _number(name: str, value: Any, lo: float, hi: float, lo_open: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    v = float(value)
    below = v <= lo if lo_open else v < lo
    if not math.isfinite(v) or below or v > hi:
        raise ValueError(f"{name} must be in {'(' if lo_open else '['}{lo:g}, {hi:g}], got {value!r}")
    return v


@dataclass(frozen=True)
class ScaleTexture:
    """Parameters of the scale texture (the fields of the C++ ``ScaleParams``).

    scales_per_unit_u : rows of scales per unit of u (along the body), in (0, 1e6].
    scales_around : scales per unit of v (around the body), integer in [3, 2^20].
    gap : gap width as a fraction of the spacing between centres, in [0, 0.5].
    jitter : centre jitter per axis as a fraction of the spacing, in [0, 0.3].
    dome : slope of a scale's surface at its rim (0 = flat), in [0, 2].
    tilt_deg : largest random tilt of a scale's normal, degrees, in [0, 45].
    thickness_jitter : film thickness factor = 1 + thickness_jitter * U[-1, 1] per scale, in [0, 0.9].
    seed : integer in [0, 2^64).
    periodic_v : v wraps with period 1 (a body of revolution), seamlessly.
    """

    scales_per_unit_u: float = 8.0
    scales_around: int = 16
    gap: float = 0.06
    jitter: float = 0.15
    dome: float = 0.25
    tilt_deg: float = 6.0
    thickness_jitter: float = 0.15
    seed: int = 0
    periodic_v: bool = True

    def __post_init__(self):
        checked = {
            "scales_per_unit_u": _number("scales_per_unit_u", self.scales_per_unit_u, 0.0, 1e6, lo_open=True),
            "scales_around": check.integer("scales_around", self.scales_around, 3, MAX_SCALES_AROUND),
            "gap": _number("gap", self.gap, 0.0, 0.5),
            "jitter": _number("jitter", self.jitter, 0.0, 0.3),
            "dome": _number("dome", self.dome, 0.0, 2.0),
            "tilt_deg": _number("tilt_deg", self.tilt_deg, 0.0, 45.0),
            "thickness_jitter": _number("thickness_jitter", self.thickness_jitter, 0.0, 0.9),
            "seed": check.integer("seed", self.seed, 0, MAX_SEED),
        }
        checked["periodic_v"] = check.flag("periodic_v", self.periodic_v)
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> ScaleTexture:
        if not isinstance(d, dict):
            raise ValueError(f"scale texture parameters must be a dict, got {type(d).__name__}")
        known = [f.name for f in fields(cls)]
        unknown = sorted(set(d) - set(known))
        if unknown:
            raise ValueError(f"unknown scale texture parameter(s) {', '.join(map(str, unknown))}; "
                             f"known: {', '.join(known)}")
        return cls(**d)

    def to_core(self) -> _core.ScaleTexture:
        """The C++ texture (built once per object)."""
        core = self.__dict__.get("_core")
        if core is None:
            params = _core.ScaleParams()
            for name, value in self.to_dict().items():
                setattr(params, name, value)
            core = _core.ScaleTexture(params)
            object.__setattr__(self, "_core", core)
        return core

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k != "_core"}

    def lookup(self, u, v) -> dict[str, np.ndarray]:
        """The texture at (u, v), arrays broadcast against each other.

        NaN or infinite coordinates give gap samples. Returns a dict of arrays of the
        broadcast shape: "gap" (bool), "id" (uint64), "slope_u", "slope_v",
        "thickness_factor", "edge_distance" (float64; see the C++ header for meanings).
        """
        try:
            uu, vv = np.broadcast_arrays(np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
        except (TypeError, ValueError) as error:
            raise ValueError(f"u and v must be real arrays that broadcast together ({error})") from None
        shape = uu.shape
        result = self.to_core().lookup(np.ascontiguousarray(uu).ravel(), np.ascontiguousarray(vv).ravel())
        names = ("gap", "id", "slope_u", "slope_v", "thickness_factor", "edge_distance")
        return {name: a.reshape(shape) for name, a in zip(names, result)}

    def scale_centre(self, i: int, j: int) -> tuple[float, float]:
        """Jittered centre (u, v) of the scale in row i, column j (unwrapped j)."""
        return self.to_core().scale_centre(int(i), int(j))

    def scale_id(self, i: int, j: int) -> int:
        """Id of the scale in row i, column j (j taken modulo scales_around when periodic)."""
        return self.to_core().scale_id(int(i), int(j))
