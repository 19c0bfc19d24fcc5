"""Named metals: measured complex indices shipped with bsdflab (see data/metals/README.md).

Each CSV file holds columns wavelength_nm, eta, k; comment lines (#) at the top give the
source publication, the digitisation used and its licence.
"""
from __future__ import annotations

from functools import cache
from importlib import resources

import numpy as np

from bsdflab.spectra import Spectrum

METALS = ("Ag", "Al", "Au", "Cu")


@cache
def _table(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    text = resources.files("bsdflab.data.metals").joinpath(f"{name}.csv").read_text()
    provenance = "\n".join(l[1:].strip() for l in text.splitlines() if l.startswith("#"))
    rows = [l for l in text.splitlines() if l and not l.startswith("#")]
    data = np.loadtxt(rows[1:], delimiter=",")  # first non-comment row is the header
    return data[:, 0], data[:, 1], data[:, 2], provenance


def metal_ior(name: str) -> tuple[Spectrum, Spectrum]:
    """(eta, k) spectra of a named metal; ValueError for an unknown name."""
    if name not in METALS:
        raise ValueError(f"unknown metal {name!r}; known metals: {', '.join(METALS)}")
    wl, eta, k, _ = _table(name)
    return Spectrum.tabulated(wl, eta, name="eta"), Spectrum.tabulated(wl, k, name="k")


def metal_provenance(name: str) -> str:
    """The source of a named metal's data, as written in its file."""
    if name not in METALS:
        raise ValueError(f"unknown metal {name!r}; known metals: {', '.join(METALS)}")
    return _table(name)[3]
