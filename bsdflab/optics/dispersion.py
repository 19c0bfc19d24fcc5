"""Dispersion models: the complex refractive index n + i k of a material versus wavelength.

Wavelengths are vacuum wavelengths in nanometres; k >= 0 means absorption (the convention
of `bsdflab.optics.fresnel`). Every model has

    index(wavelength_nm) -> complex ndarray of the same shape
    to_dict() -> plain dict,  Model.from_dict(d) / dispersion_from_dict(d) -> model

Models
------
Constant(n, k=0)
    The same index at every wavelength.
Cauchy(A, B, C=0)
    n = A + B / lambda^2 + C / lambda^4 with lambda in nm (B in nm^2, C in nm^4), k = 0.
    Keratin, for example, is about Cauchy(1.532, 5890): n(550 nm) = 1.5515.
Tabulated(wavelengths_nm, n, k)
    Linear interpolation between samples; held constant beyond the first and last sample,
    like `bsdflab.spectra.Spectrum.tabulated`.
"""
from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from bsdflab.util import args as check
from bsdflab.util.args import MAX_EXTINCTION, MAX_IOR, MIN_IOR, real_array, real_scalar
from bsdflab.util.deprecation import renamed_key


def wavelengths_nm(value: Any, name: str = "wavelength_nm") -> np.ndarray:
    """Validated wavelengths in nm (any shape), within [1, 1e12] nm (docs/limits.md)."""
    return check.wavelengths_nm(name, value)


class Dispersion(abc.ABC):
    """Base of the dispersion models; see the module docstring."""

    type_name: ClassVar[str]  # the dict tag, "type" (as for BSDFs)

    @abc.abstractmethod
    def index(self, wavelength_nm) -> np.ndarray:
        """Complex index n + i k at the given wavelengths (nm)."""

    @abc.abstractmethod
    def to_dict(self) -> dict[str, Any]:
        """The model as a plain dict (inverse of dispersion_from_dict)."""


@dataclass(frozen=True)
class Constant(Dispersion):
    """A wavelength-independent index n + i k.

    Parameters
    ----------
    n : float
        Real part, in [1e-3, 1e3].
    k : float, optional
        Extinction coefficient, in [0, 1e3] (default 0, lossless).
    """

    n: float
    k: float = 0.0
    type_name: ClassVar[str] = "constant"

    def __post_init__(self):
        object.__setattr__(self, "n", real_scalar("n", self.n, MIN_IOR, MAX_IOR))
        object.__setattr__(self, "k", real_scalar("k", self.k, 0.0, MAX_EXTINCTION))

    def index(self, wavelength_nm) -> np.ndarray:
        wl = wavelengths_nm(wavelength_nm)
        return np.full(wl.shape, complex(self.n, self.k))

    def to_dict(self) -> dict[str, Any]:
        return {"type": self.type_name, "n": self.n, "k": self.k}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Constant:
        return cls(d["n"], d.get("k", 0.0))


@dataclass(frozen=True)
class Cauchy(Dispersion):
    """Cauchy's law n = A + B / lambda^2 + C / lambda^4 (lambda in nm), lossless.

    Parameters
    ----------
    A : float
        Constant term, finite.
    B : float
        Coefficient of lambda^-2 in nm^2, finite.
    C : float, optional
        Coefficient of lambda^-4 in nm^4, finite (default 0).

    `index` raises ValueError where the resulting n is outside [1e-3, 1e3].
    """

    A: float
    B: float
    C: float = 0.0
    type_name: ClassVar[str] = "cauchy"

    def __post_init__(self):
        for name in ("A", "B", "C"):
            object.__setattr__(self, name, real_scalar(name, getattr(self, name)))

    def index(self, wavelength_nm) -> np.ndarray:
        wl2 = wavelengths_nm(wavelength_nm) ** 2
        n = self.A + self.B / wl2 + self.C / (wl2 * wl2)
        if np.any(n < MIN_IOR) or np.any(n > MAX_IOR):
            raise ValueError(f"Cauchy index A + B/lambda^2 + C/lambda^4 must be in [{MIN_IOR:g}, "
                             f"{MAX_IOR:g}]; got {n.min():g} to {n.max():g} for A={self.A}, "
                             f"B={self.B}, C={self.C}")
        return n.astype(np.complex128)

    def to_dict(self) -> dict[str, Any]:
        return {"type": self.type_name, "A": self.A, "B": self.B, "C": self.C}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Cauchy:
        return cls(d["A"], d["B"], d.get("C", 0.0))


class Tabulated(Dispersion):
    """Measured n and k at given wavelengths, linearly interpolated.

    Parameters
    ----------
    wavelengths_nm : array_like, shape (M,)
        Strictly increasing, finite, > 0 nm; M >= 2.
    n : array_like, shape (M,)
        Real parts, finite and > 0.
    k : array_like, shape (M,), optional
        Extinction coefficients, finite and >= 0 (default zeros).

    Outside [wavelengths_nm[0], wavelengths_nm[-1]] the end values are held.
    """

    type_name: ClassVar[str] = "tabulated"

    def __init__(self, wavelengths_nm, n, k=None):
        self.wavelengths_nm = real_array("wavelengths_nm", wavelengths_nm, check.MIN_WAVELENGTH_NM,
                                         check.MAX_WAVELENGTH_NM, ndim=1)
        self.n = real_array("n", n, MIN_IOR, MAX_IOR, ndim=1)
        self.k = np.zeros_like(self.n) if k is None else real_array("k", k, 0.0, MAX_EXTINCTION, ndim=1)
        m = len(self.wavelengths_nm)
        if m < 2:
            raise ValueError(f"wavelengths_nm must have at least 2 samples, got {m}")
        if self.n.shape != (m,) or self.k.shape != (m,):
            raise ValueError(f"wavelengths_nm, n and k must have equal length; got {m}, "
                             f"{len(self.n)} and {len(self.k)}")
        if np.any(np.diff(self.wavelengths_nm) <= 0):
            raise ValueError("wavelengths_nm must be strictly increasing")
        # private, read-only copies: immutable like the other models
        self.wavelengths_nm, self.n, self.k = (np.array(a) for a in (self.wavelengths_nm,
                                                                      self.n, self.k))
        for a in (self.wavelengths_nm, self.n, self.k):
            a.setflags(write=False)

    def index(self, wavelength_nm) -> np.ndarray:
        wl = wavelengths_nm(wavelength_nm)
        return (np.interp(wl, self.wavelengths_nm, self.n)
                + 1j * np.interp(wl, self.wavelengths_nm, self.k))

    def to_dict(self) -> dict[str, Any]:
        return {"type": self.type_name, "wavelengths_nm": self.wavelengths_nm.tolist(),
                "n": self.n.tolist(), "k": self.k.tolist()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Tabulated:
        return cls(d["wavelengths_nm"], d["n"], d.get("k"))

    def __eq__(self, other):
        return (isinstance(other, Tabulated)
                and all(np.array_equal(getattr(self, a), getattr(other, a))
                        for a in ("wavelengths_nm", "n", "k")))

    def __hash__(self):
        return hash((self.wavelengths_nm.tobytes(), self.n.tobytes(), self.k.tobytes()))

    def __repr__(self):
        wl = self.wavelengths_nm
        return f"Tabulated({len(wl)} samples, {wl[0]:g}-{wl[-1]:g} nm)"


_MODELS = {m.type_name: m for m in (Constant, Cauchy, Tabulated)}


def dispersion_from_dict(d: dict[str, Any]) -> Dispersion:
    """The model a `to_dict()` result describes; ValueError for an unknown model. Dicts
    tagged ``"model"`` (before issue 34) still read, with a FutureWarning."""
    if isinstance(d, dict):
        d = renamed_key(d, "model", "type", "dispersion ")
    if not isinstance(d, dict) or d.get("type") not in _MODELS:
        known = ", ".join(sorted(_MODELS))
        raise ValueError(f"a dispersion dict needs 'type' in ({known}); got {check.brief(d)}")
    try:
        return _MODELS[d["type"]].from_dict(d)
    except KeyError as e:
        raise ValueError(f"dispersion dict of type {d['type']!r} lacks the key {e}") from None
    except (TypeError, AttributeError) as e:
        raise ValueError(f"bad dispersion dict of type {d['type']!r}: {check.one_line(e)}") from None


def as_dispersion(value: Any, name: str) -> Dispersion:
    """A model from a model, a dict, or a real or complex number n + i k (-> Constant)."""
    if isinstance(value, Dispersion):
        return value
    if isinstance(value, dict):
        return dispersion_from_dict(value)
    if np.ndim(value) == 0 and isinstance(value, (int, float, complex, np.number, np.ndarray)):
        try:
            z = complex(value)
        except (OverflowError, TypeError, ValueError):
            raise ValueError(f"{name} must be a finite number, got {check.brief(value)}") from None
        if not (math.isfinite(z.real) and math.isfinite(z.imag)):
            raise ValueError(f"{name} must be finite, got {value!r}")
        if z.real <= 0:
            raise ValueError(f"{name} must have a real part n > 0, got {value!r}")
        if z.imag < 0:
            raise ValueError(f"{name} must have an imaginary part k >= 0 (absorbing), "
                             f"got {value!r}")
        if not MIN_IOR <= z.real <= MAX_IOR or z.imag > MAX_EXTINCTION:
            raise ValueError(f"{name} must have n in [{MIN_IOR:g}, {MAX_IOR:g}] and k in "
                             f"[0, {MAX_EXTINCTION:g}] (docs/limits.md), got {value!r}")
        return Constant(z.real, z.imag)
    raise ValueError(f"{name} must be a number n + i k, a dict or a Dispersion model; "
                     f"got {type(value).__name__}")
