"""A slab between two interfaces of a layered BSDF: thickness, absorption, scattering.

Units: thickness in micrometres (um); absorption and scattering coefficients in 1/um.
sigma_a may vary with wavelength (a Spectrum); sigma_s is grey (one number), which lets
the estimator sample free flights exactly by sigma_s and carry absorption as a weight.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsdflab.spectra import Spectrum
from bsdflab.util.args import real_scalar

PHASE_KINDS = {"isotropic": 0, "hg": 1, "vmf": 2}


@dataclass(frozen=True)
class PhaseFunction:
    """Isotropic, Henyey-Greenstein (``g`` in (-1, 1)) or von Mises-Fisher (``kappa`` >= 0,
    a forward-peaked lobe)."""

    type: str = "isotropic"
    g: float = 0.0
    kappa: float = 0.0

    def __post_init__(self):
        if self.type not in PHASE_KINDS:
            raise ValueError(f"phase type must be one of {', '.join(PHASE_KINDS)}, got {self.type!r}")
        object.__setattr__(self, "g", real_scalar("g", self.g, -1.0, 1.0, lo_open=True, hi_open=True))
        object.__setattr__(self, "kappa", real_scalar("kappa", self.kappa, 0.0, 1e6))

    @property
    def core_kind(self) -> int:
        return PHASE_KINDS[self.type]

    @property
    def core_parameter(self) -> float:
        return {"isotropic": 0.0, "hg": self.g, "vmf": self.kappa}[self.type]

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"type": self.type}
        if self.type == "hg":
            d["g"] = self.g
        if self.type == "vmf":
            d["kappa"] = self.kappa
        return d

    @classmethod
    def coerce(cls, value) -> PhaseFunction:
        if value is None:
            return cls()
        if isinstance(value, PhaseFunction):
            return value
        if isinstance(value, dict):
            unknown = set(value) - {"type", "g", "kappa"}
            if unknown:
                raise ValueError(f"unknown phase function parameters: {', '.join(sorted(unknown))}")
            return cls(**value)
        raise ValueError(f"phase must be None, a dict or a PhaseFunction, got {value!r}")


@dataclass(frozen=True)
class Slab:
    """A homogeneous slab.

    Parameters
    ----------
    thickness_um : float >= 0
        Thickness in micrometres.
    sigma_a : number, dict or Spectrum >= 0
        Absorption coefficient in 1/um (spectral).
    sigma_s : float >= 0
        Scattering coefficient in 1/um (grey).
    phase : PhaseFunction or dict
        Phase function of the scattering.
    """

    thickness_um: float = 1.0
    sigma_a: Any = 0.0
    sigma_s: float = 0.0
    phase: Any = field(default_factory=PhaseFunction)

    def __post_init__(self):
        object.__setattr__(self, "thickness_um", real_scalar("thickness_um", self.thickness_um, 0.0, 1e6))
        object.__setattr__(self, "sigma_a", Spectrum.coerce(self.sigma_a, "sigma_a", 0.0))
        object.__setattr__(self, "sigma_s", real_scalar("sigma_s", self.sigma_s, 0.0, 1e6))
        object.__setattr__(self, "phase", PhaseFunction.coerce(self.phase))

    @classmethod
    def from_albedo(cls, thickness_um: float, albedo: float, sigma_t: float, phase=None) -> Slab:
        """A grey slab given its single-scattering albedo in [0, 1] and extinction
        coefficient sigma_t (1/um): sigma_s = albedo sigma_t, sigma_a = (1 - albedo) sigma_t."""
        a = real_scalar("albedo", albedo, 0.0, 1.0)
        t = real_scalar("sigma_t", sigma_t, 0.0, 1e6)
        return cls(thickness_um, sigma_a=(1.0 - a) * t, sigma_s=a * t, phase=phase)

    def sigma_a_at(self, wavelengths) -> np.ndarray:
        return self.sigma_a.at(wavelengths)

    def to_dict(self) -> dict[str, Any]:
        return {"thickness_um": self.thickness_um, "sigma_a": self.sigma_a.to_dict(),
                "sigma_s": self.sigma_s, "phase": self.phase.to_dict()}

    @classmethod
    def coerce(cls, value, index: int) -> Slab:
        if isinstance(value, Slab):
            return value
        if isinstance(value, dict):
            unknown = set(value) - {"thickness_um", "sigma_a", "sigma_s", "phase"}
            if unknown:
                raise ValueError(f"slabs[{index}]: unknown parameters {', '.join(sorted(unknown))}")
            return cls(**value)
        raise ValueError(f"slabs[{index}] must be a Slab or a dict, got {value!r}")
