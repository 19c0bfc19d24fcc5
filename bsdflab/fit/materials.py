"""Named materials of the fit's structures, with their dispersion and sources.

Every material gives its complex index n + i k at any wavelengths (nm), vectorised over
parameter sets: ``index(values, wl)`` with ``values`` {coefficient: (P,) array} and ``wl``
(P, E) -> complex (P, E). A named material's coefficients are fixed (its published
dispersion); a material written as numbers in the TOML has free coefficients, which the
structure exposes as fit parameters (``<medium>_ior``, ``<medium>_cauchy_b``, ...).

Sources of the named materials
------------------------------
air        n = 1.000277 (the presets' value, bsdflab.presets.AIR_IOR; dispersion < 1e-5 in
           the visible, negligible for films)
keratin    n = 1.532 + 5890 / lambda^2 (Leertouwer, Wilts & Stavenga 2011, Opt. Express
           19:24061; bird feather keratin)
chitin     n = 1.517 + 8800 / lambda^2 (same source; butterfly wing chitin)
guanine    n = 1.83, non-dispersive (Levy-Lior et al. 2008, Cryst. Growth Des. 8:507: the
           in-plane index of biogenic beta-guanine platelets; no dispersion is published)
eumelanin  n = 1.648 + 23700 / lambda^2, k = 0.56 exp(-lambda / 270 nm) (Stavenga,
           Leertouwer, Osorio & Wilts 2015, Light Sci. Appl. 4:e243)
water      n = 1.3237 + 3088 / lambda^2: the two-term Cauchy through Hale & Querry's (1973,
           Appl. Opt. 12:555) 1.343 at 400 nm and 1.330 at 700 nm (within 1e-3 between)
cytoplasm  n = 1.33 (bsdflab.presets.CYTOPLASM_IOR; the gap index used for iridophore
           stacks, e.g. Land 1972, Prog. Biophys. Mol. Biol. 24:75)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bsdflab import presets


@dataclass(frozen=True)
class Coefficient:
    key: str           # suffix of the fit parameter: <medium>_<key>
    default: float
    lo: float
    hi: float
    description: str


@dataclass(frozen=True)
class Material:
    """n = A + B / lambda^2 + C / lambda^4 + i (k + k_amp exp(-lambda / k_decay))."""

    label: str
    A: float
    B: float = 0.0
    C: float = 0.0
    k: float = 0.0
    k_amp: float = 0.0
    k_decay_nm: float = 1.0
    free: tuple[str, ...] = ()      # coefficient keys exposed as fit parameters

    def coefficients(self) -> tuple[Coefficient, ...]:
        table = {
            "ior": Coefficient("ior", self.A, 0.0, 10.0, "index n (Cauchy A)"),
            "cauchy_b": Coefficient("cauchy_b", self.B, -1e6, 1e6, "Cauchy B, nm^2"),
            "cauchy_c": Coefficient("cauchy_c", self.C, -1e12, 1e12, "Cauchy C, nm^4"),
            "k": Coefficient("k", self.k, 0.0, 10.0, "extinction coefficient k"),
        }
        return tuple(table[key] for key in self.free)

    def index(self, values: dict[str, np.ndarray], wl: np.ndarray) -> np.ndarray:
        """Complex index (P, E) at wavelengths ``wl`` (P, E); ``values`` holds the free
        coefficients as (P,) arrays."""
        def coef(key, fixed):
            v = values.get(key)
            return fixed if v is None else np.asarray(v, float)[:, None]
        inv2 = 1.0 / (wl * wl)
        n = coef("ior", self.A) + coef("cauchy_b", self.B) * inv2 + coef("cauchy_c", self.C) * inv2 * inv2
        k = coef("k", self.k) + (self.k_amp * np.exp(-wl / self.k_decay_nm) if self.k_amp else 0.0)
        return n + 1j * (k + np.zeros_like(wl))


NAMED = {
    "air": Material("air", presets.AIR_IOR),
    "keratin": Material("keratin", presets.KERATIN_CAUCHY["A"], presets.KERATIN_CAUCHY["B"]),
    "chitin": Material("chitin", 1.517, 8800.0),
    "guanine": Material("guanine", presets.GUANINE_IOR),
    "eumelanin": Material("eumelanin", 1.648, 23700.0, k_amp=0.56, k_decay_nm=270.0),
    "water": Material("water", 1.3237, 3088.0),
    "cytoplasm": Material("cytoplasm", presets.CYTOPLASM_IOR),
}


def material(where: str, spec) -> Material:
    """A material from its TOML form: a name of NAMED, a number (n), {n = .., k = ..} or
    {cauchy = [A, B] or [A, B, C], k = ..}. Numbers make free coefficients."""
    def real(key, v, lo, hi):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not lo <= v <= hi:
            raise ValueError(f"{where}: {key} must be a finite number in [{lo:g}, {hi:g}], got {v!r}")
        return float(v)

    if isinstance(spec, str):
        if spec not in NAMED:
            raise ValueError(f"{where}: unknown material {spec!r}; named: {', '.join(NAMED)} "
                             "(or a number, {n, k} or {cauchy = [A, B, C], k})")
        return NAMED[spec]
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return Material(f"n = {spec:g}", real("material", spec, 1e-3, 10.0), free=("ior",))
    if isinstance(spec, dict):
        extra = set(spec) - {"n", "k", "cauchy"}
        if extra or ("n" in spec) == ("cauchy" in spec):
            raise ValueError(f"{where}: a material table has n or cauchy (one of them) and optionally k, "
                             f"got keys {sorted(spec)}")
        k = real("k", spec.get("k", 0.0), 0.0, 10.0)
        if "n" in spec:
            n = real("n", spec["n"], 1e-3, 10.0)
            return Material(f"n = {n:g} + {k:g}i", n, k=k, free=("ior", "k"))
        c = spec["cauchy"]
        if not isinstance(c, list) or len(c) not in (2, 3):
            raise ValueError(f"{where}: cauchy must be [A, B] or [A, B, C] (nm^2, nm^4), got {c!r}")
        A, B = real("cauchy A", c[0], 1e-3, 10.0), real("cauchy B", c[1], -1e6, 1e6)
        C = real("cauchy C", c[2], -1e12, 1e12) if len(c) == 3 else 0.0
        free = ("ior", "cauchy_b", "cauchy_c", "k") if len(c) == 3 else ("ior", "cauchy_b", "k")
        return Material(f"Cauchy({A:g}, {B:g}, {C:g}) + {k:g}i", A, B, C, k=k, free=free)
    raise ValueError(f"{where}: material must be a name, a number or a table, got {spec!r}")
