"""Spectral parameters: a value that may depend on wavelength.

A `Spectrum` is one of
  * constant     -- the same value at every wavelength;
  * rgb          -- a linear sRGB triple, lifted to a spectrum (Mallett-Yuksel 2019);
  * tabulated    -- samples (wavelengths in nm, values), linearly interpolated, held
                    constant beyond the ends.
It serialises to a plain dict (see `to_dict`).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab.spectra.colour_weights import rgb_to_spectrum
from bsdflab.util.args import real_array, real_scalar


class Spectrum:
    def __init__(self, kind: str, data: dict[str, Any]):
        self.kind = kind
        self._data = data

    # -- constructors -----------------------------------------------------------------
    @classmethod
    def constant(cls, value: float, name: str = "value", lo=None, hi=None) -> Spectrum:
        return cls("constant", {"value": real_scalar(name, value, lo, hi)})

    @classmethod
    def rgb(cls, rgb, name: str = "rgb", lo=0.0, hi=1.0) -> Spectrum:
        a = real_array(name, rgb, lo, hi, ndim=1)
        if a.shape != (3,):
            raise ValueError(f"{name} as RGB must have 3 entries, got {a.shape[0]}")
        return cls("rgb", {"rgb": a})

    @classmethod
    def tabulated(cls, wavelengths, values, name: str = "values", lo=None, hi=None) -> Spectrum:
        wl = real_array(f"{name}.wavelengths", wavelengths, 0.0, lo_open=True, ndim=1)
        v = real_array(name, values, lo, hi, ndim=1)
        if wl.shape != v.shape:
            raise ValueError(f"{name}: wavelengths and values must have equal length, "
                             f"got {wl.shape[0]} and {v.shape[0]}")
        if np.any(np.diff(wl) <= 0):
            raise ValueError(f"{name}.wavelengths must be strictly increasing")
        return cls("tabulated", {"wavelengths": wl, "values": v})

    @classmethod
    def coerce(cls, value: Any, name: str, lo=None, hi=None, lo_open: bool = False) -> Spectrum:
        """A Spectrum from a number, an RGB triple, a dict or a Spectrum; range-checked."""
        if isinstance(value, Spectrum):
            s = value
        elif isinstance(value, dict):
            s = cls.from_dict(value)
        elif np.ndim(value) == 0:
            s = cls.constant(value, name)
        elif np.shape(value) == (3,):
            s = cls.rgb(value, name, None, None)
        else:
            raise ValueError(f"{name} must be a number, an RGB triple, a dict or a Spectrum; "
                             f"got shape {np.shape(value)}")
        s.check_range(name, lo, hi, lo_open)
        return s

    # -- evaluation -------------------------------------------------------------------
    def at(self, wavelengths) -> np.ndarray:
        """Values at `wavelengths` (nm), shape (L,)."""
        wl = np.asarray(wavelengths, dtype=np.float64)
        if self.kind == "constant":
            return np.full(wl.shape, self._data["value"])
        if self.kind == "rgb":
            return rgb_to_spectrum(self._data["rgb"], wl)
        return np.interp(wl, self._data["wavelengths"], self._data["values"])

    def check_range(self, name: str, lo=None, hi=None, lo_open: bool = False) -> None:
        values = {"constant": lambda d: np.array([d["value"]]), "rgb": lambda d: d["rgb"],
                  "tabulated": lambda d: d["values"]}[self.kind](self._data)
        real_array(name, values, lo, hi, lo_open=lo_open)

    # -- serialisation ----------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"type": self.kind}
        for k, v in self._data.items():
            out[k] = v.tolist() if isinstance(v, np.ndarray) else v
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Spectrum:
        if not isinstance(d, dict) or "type" not in d:
            raise ValueError("a spectrum dict needs a 'type' of 'constant', 'rgb' or 'tabulated'")
        kind = d["type"]
        if kind == "constant":
            return cls.constant(d.get("value"))
        if kind == "rgb":
            return cls.rgb(d.get("rgb"), hi=None)
        if kind == "tabulated":
            return cls.tabulated(d.get("wavelengths"), d.get("values"))
        raise ValueError(f"unknown spectrum type {kind!r}; expected 'constant', 'rgb' or 'tabulated'")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Spectrum) and self.to_dict() == other.to_dict()

    def __repr__(self) -> str:
        return f"Spectrum({self.to_dict()})"
