"""The export targets: each standard's own thin-film reflectance model and parameter ranges.

A target's model is the comparison model of ``bsdflab.reference.approximations`` that
implements what that standard (or tool) computes; the fit chooses the target's parameters
with it. Ranges are the standards' hard limits (the fit stays inside them), with the
published units: OpenPBR's thin_film_thickness is in micrometres, glTF's and Blender's in nm.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Target:
    name: str                       # what the file is (for reports)
    model_name: str                 # the comparison model the fit uses
    model: Callable                 # (n_outer, n_film, n_base, thickness_nm, cos) -> (..., 3) linear sRGB
    thickness_nm: tuple[float, float]
    film_ior: tuple[float, float]
    base_ior: tuple[float, float]
    suffixes: tuple[str, ...]       # file names the writer accepts

    def clip(self, x: np.ndarray) -> np.ndarray:
        lo = np.array([self.thickness_nm[0], self.film_ior[0], self.base_ior[0]])
        hi = np.array([self.thickness_nm[1], self.film_ior[1], self.base_ior[1]])
        return np.clip(x, lo, hi)


def _materialx(n1, n2, n3, d, c):
    from bsdflab.reference.approximations import belcour_barla_rgb

    return belcour_barla_rgb(n1, n2, n3, d, c, terms=2, sensitivity="gaussian")


def _gltf(n1, n2, n3, d, c):
    from bsdflab.reference.approximations import gltf_iridescence_rgb

    return gltf_iridescence_rgb(n1, n2, n3, d, c)


def _cycles(n1, n2, n3, d, c):
    from bsdflab.reference.approximations.cycles import cycles_thin_film_rgb

    return cycles_thin_film_rgb(n1, n2, n3, d, c)


_OPENPBR = dict(model_name="Belcour-Barla as MaterialX mx_fresnel_airy computes it (Gaussian XYZ fit, 2 terms, "
                           "CIE RGB)", model=_materialx, thickness_nm=(0.0, 1e5), film_ior=(1.0, 3.0),
                base_ior=(1.0, 3.0))
TARGETS = {
    "openpbr": Target("MaterialX 1.39 document, OpenPBR Surface (open_pbr_surface)", suffixes=(".mtlx",), **_OPENPBR),
    "usd": Target("USD (usda) with the OpenPBR MaterialX material", suffixes=(".usda",), **_OPENPBR),
    "gltf": Target("glTF 2.0 with KHR_materials_iridescence / _ior / _specular",
                   "glTF KHR_materials_iridescence (Schlick, Gaussian fit, 2 terms)", _gltf,
                   thickness_nm=(0.0, 1e5), film_ior=(1.0, 3.0), base_ior=(1.0, 3.0),
                   suffixes=(".gltf", ".glb")),
    "blender": Target("Blender .blend, Principled BSDF with Thin Film",
                      "Cycles thin film (tabulated CIE 1931 Fourier sensitivities, 3 terms)", _cycles,
                      thickness_nm=(0.0, 1e5), film_ior=(1.0, 3.0), base_ior=(1.0, 3.0),
                      suffixes=(".blend",)),
}
FORMATS = tuple(TARGETS)


def target(name: str) -> Target:
    if name not in TARGETS:
        raise ValueError(f"unknown format {name!r}; known formats: {', '.join(TARGETS)}")
    return TARGETS[name]

