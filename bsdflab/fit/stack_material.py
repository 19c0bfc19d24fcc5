"""A smooth structure fit's parameter set as a renderable bsdflab model dict (what a smooth
structure study writes as material.json; docs/fit.md, "Structures and instruments").

The smooth model reflects the exterior | layers | substrate stack's specular beam and loses
the light refracted into the semi-infinite substrate. In the BSDF registry that is a
``layered`` model: a smooth ``dielectric`` top (exterior -> substrate index) carrying the
layers as its film, over a slab of zero thickness and a black Lambertian base, so nothing
that enters comes back (the top's delta reflection is the stack's R; the scattered part is
0). It is the representation ``bsdflab export`` (a dielectric top over a diffuse base) and
the renderer take.

What it carries exactly: the layers' thicknesses and indices (a lossless Cauchy film as a
Cauchy dict, an absorbing one as n + ik tabulated at 5 nm over 350-1000 nm, as the full
model's). What it cannot: a dispersive or absorbing exterior or substrate (the dielectric's
indices are real numbers: read at ``REFERENCE_NM``, the full model's convention), the
thickness spread (a spatial average over the spot: the mean thickness is used) and the
instrument (scale, background, offset, slit, cone describe the measurement, not the material).
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.material import SIGMA_A_GRID_NM
from bsdflab.fit.structure import Medium, Structure

REFERENCE_NM = 550.0
# PFMC walks per evaluation: every walk ends at the black base, so the scattered part is
# exactly 0 whatever the count, and one walk is exact (a 256 x 256, 16 spp sphere renders
# bit-identically to 256 walks, 18 s instead of 549 s on the loaded 2-core machine)
SAMPLES = 1


def _coefficients(m: Medium, v: dict, prefix: str, skip=()) -> dict:
    return {c.key: v[f"{prefix}_{c.key}"] for c in m.material.coefficients() if c.key not in skip}


def real_index(m: Medium, v: dict, prefix: str) -> float:
    """The medium's real index at REFERENCE_NM (its k left out)."""
    coef = _coefficients(m, v, prefix, skip=("k",))
    n = m.material.index({k: np.array([x]) for k, x in coef.items()}, np.array([[REFERENCE_NM]]))
    return float(n.real[0, 0])


def is_constant_real(m: Medium, v: dict, prefix: str, skip=()) -> bool:
    """Whether the medium's index is one real number over SIGMA_A_GRID_NM (then a real index is exact)."""
    coef = _coefficients(m, v, prefix, skip)
    n = m.material.index({k: np.array([x]) for k, x in coef.items()}, SIGMA_A_GRID_NM[None, :])[0]
    return bool(np.ptp(n.real) == 0.0 and not np.any(n.imag))


def film_material(m: Medium, v: dict) -> dict:
    """A layer's index as the engine's dispersion dict: Cauchy when lossless, else n + ik
    tabulated on SIGMA_A_GRID_NM."""
    mat = m.material
    coef = _coefficients(m, v, m.name)
    if coef.get("k", mat.k) == 0 and not mat.k_amp:
        return {"type": "cauchy", "A": coef.get("ior", mat.A), "B": coef.get("cauchy_b", mat.B),
                "C": coef.get("cauchy_c", mat.C)}
    wl = SIGMA_A_GRID_NM
    n = mat.index({key: np.array([x]) for key, x in coef.items()}, wl[None, :])[0]
    return {"type": "tabulated", "wavelengths_nm": wl.tolist(), "n": n.real.tolist(), "k": n.imag.tolist()}


def film(s: Structure, v: dict) -> list[dict] | None:
    """The layers top to bottom at their mean thicknesses (zero-thickness layers left out)."""
    out = [{"material": film_material(s.layers[i], v), "thickness_nm": v[f"{s.layers[i].name}_thickness_nm"]}
           for i in s.order if v[f"{s.layers[i].name}_thickness_nm"] > 0]
    return out or None


def stack_material_dict(s: Structure, v: dict, samples: int = SAMPLES) -> dict:
    """The ``layered`` model dict of one parameter set ``v`` (name -> value; module docstring)."""
    top = {"type": "dielectric", "int_ior": real_index(s.substrate, v, "substrate"),
           "ext_ior": real_index(s.exterior, v, "exterior"), "film": film(s, v)}
    return {"type": "layered", "interfaces": [top], "slabs": [{"thickness_um": 0.0}],
            "base": {"type": "diffuse", "reflectance": 0.0}, "samples": samples}


def stack_material_note(s: Structure, v: dict) -> str:
    """What material.json carries of this fit, for summary.json."""
    parts = ["material.json: the posterior median as a layered model (a smooth dielectric top carrying the "
             "layers as its film, over a black base: the light refracted into the substrate does not come back, "
             "as in the smooth model); its specular reflectance is the fitted stack's without the instrument "
             "(scale, background, angle offset, slit and cone describe the measurement, not the material)"]
    spread = [s.layers[i].name for i in s.spread_layers() if v[f"{s.layers[i].name}_thickness_spread_nm"] > 0]
    if spread:
        parts.append(f"the thickness spread of {', '.join(spread)} is a spatial average over the spot, which one "
                     "BSDF cannot carry: the mean thickness is used")
    inexact = [name for name, m, skip in (("exterior", s.exterior, ("k",)), ("substrate", s.substrate, ()))
               if not is_constant_real(m, v, name, skip)]
    if inexact:
        parts.append(f"the {' and '.join(inexact)} index is dispersive or absorbing: material.json takes its real "
                     f"part at {REFERENCE_NM:g} nm")
    return "; ".join(parts)
