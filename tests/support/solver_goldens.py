"""Golden outputs of the adding-doubling solver, for refactors that must not change a bit
(tests/solvers/test_solver_goldens.py compares them exactly).

Every path of the solve is covered: smooth tops (Nystrom extras), rough tops (product
integration, the shared inner reflection, ``with_model``), films, Beckmann and GGX,
isotropic, HG and non-scattering slabs, interior interfaces (matched smooth, film-coated,
rough), opaque bases (Lambertian, conductor, rough conductor), rough dielectric bases,
two-sided stacks (all four kinds of pairs), the spectral interpolation of what lies below
a rough top (``spectral_stride``), the coarse check solve (``eval_with_error``) and
``scattered_only``.

Regenerate (only when a change of the numbers is intended, and say why in the commit):
    python tests/support/solver_goldens.py
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np

import bsdflab as bl
from bsdflab.solvers import solve
from bsdflab.testing import random_unit_vectors, spherical_directions

PATH = Path(__file__).resolve().parents[1] / "solvers" / "solver_goldens.json"
WL = [450.0, 550.0, 650.0]
WL9 = [400.0, 440.0, 480.0, 520.0, 560.0, 600.0, 640.0, 680.0, 720.0]
FILM = [{"material": 1.83, "thickness_nm": 400.0}]
HG = bl.Slab(2.0, sigma_a=0.1, sigma_s=0.5, phase={"type": "hg", "g": 0.6})
ISO = bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0)
CLEAR = bl.Slab(0.5, sigma_a=0.3, sigma_s=0.0)


def _rough(alpha, n=1.5, ext=1.0, **kw):
    return bl.RoughDielectric(alpha, int_ior=n, ext_ior=ext, **kw)


# name -> (model, solve keywords, wavelengths)
CASES = {
    "smooth/hg/diffuse": (lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [HG], bl.Diffuse(0.5)), {}, WL),
    "smooth film/iso/conductor film": (
        lambda: bl.Layered(
            [bl.Dielectric(1.5, 1.0, film=FILM)], [ISO], bl.Conductor(material="Au", ext_ior=1.5, film=FILM)
        ),
        {},
        WL,
    ),
    "smooth/clear/roughconductor": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [CLEAR], bl.RoughConductor(0.3, material="Cu", ext_ior=1.5)),
        {},
        WL,
    ),
    "smooth/hg/matched film/iso/diffuse": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.5, 1.5, film=FILM)], [HG, ISO], bl.Diffuse(0.3)),
        {},
        WL,
    ),
    "ggx 0.2/hg/diffuse": (lambda: bl.Layered([_rough(0.2)], [HG], bl.Diffuse(0.5)), {}, WL),
    "beckmann 0.5/iso/roughdielectric": (
        lambda: bl.Layered([_rough(0.5, distribution="beckmann")], [ISO], _rough(0.4, 1.0, 1.5)),
        {},
        WL,
    ),
    "ggx 0.1 film/hg/diffuse stride 2": (
        lambda: bl.Layered([_rough(0.1, film=FILM)], [HG], bl.Diffuse(0.5)),
        {"spectral_stride": 2, "film_lookup": True},
        WL9,
    ),
    "xenopeltis": (lambda: bl.presets.preset("xenopeltis"), {}, WL),
    "two-sided smooth/hg/water": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [HG], bl.Dielectric(1.33, 1.5)),
        {},
        WL,
    ),
    "two-sided film/iso/air": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0, film=FILM)], [ISO], bl.Dielectric(1.0, 1.5)),
        {},
        WL,
    ),
    "two-sided smooth/hg/ggx 0.5 1.5-2.0/iso/air": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0), _rough(0.5, 2.0, 1.5)], [HG, ISO], bl.Dielectric(1.0, 2.0)),
        {"nodes": 20},
        WL,
    ),
    "smooth/hg/ggx 0.5 1.5-2.0/iso/diffuse": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0), _rough(0.5, 2.0, 1.5)], [HG, ISO], bl.Diffuse(0.4)),
        {},
        WL,
    ),
    "smooth/hg/diffuse orders 5 thin 2^-10": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [HG], bl.Diffuse(0.5)),
        {"orders": 5, "thin_depth": 2.0**-10, "azimuth_samples": 64},
        WL,
    ),
}
# A rough top swapped by ``with_model`` (another film thickness over the same inner stack).
WITH_MODEL = (
    "xenopeltis",
    lambda m: bl.Layered(
        [
            bl.RoughDielectric(
                m.interfaces[0].alpha,
                int_ior=m.interfaces[0].int_ior,
                ext_ior=m.interfaces[0].ext_ior,
                film=[{"material": 1.83, "thickness_nm": 250.0}],
            )
        ],
        list(m.slabs),
        m.base,
    ),
)


def pairs(two_sided: bool) -> tuple[np.ndarray, np.ndarray]:
    """Upper-hemisphere pairs with grazing ones; for two-sided stacks every kind of pair."""
    wi = random_unit_vectors(8, seed=3, hemisphere="upper")
    wo = random_unit_vectors(8, seed=4, hemisphere="upper")
    graze = spherical_directions(np.radians([86.0, 88.0]), [0.5, 2.0])
    wi[:2], wo[2:4] = graze, graze
    if not two_sided:
        return wi, wo
    flip = np.array([1.0, 1.0, -1.0])
    wi2, wo2 = wi.copy(), wo.copy()
    wi2[::2] *= flip  # viewer below: transmission down / reflection from below
    wo2[1::2] *= flip  # light below
    wi3, wo3 = wi * flip, wo * flip  # reflection from below
    return np.vstack([wi, wi2, wi3]), np.vstack([wo, wo2, wo3])


def outputs(name: str) -> dict:
    make, kw, wl = CASES[name]
    model = make()
    sol = solve(model, wl, **kw)
    wi, wo = pairs(sol.two_sided)
    value, bound = sol.eval_with_error(wi, wo)
    out = {
        "orders": sol.orders,
        "azimuth_samples": sol.azimuth_samples,
        "two_sided": sol.two_sided,
        "eval": sol.eval(wi, wo).tolist(),
        "eval_with_error": [value.tolist(), bound.tolist()],
        "scattered_only": sol.eval(wi, wo, scattered_only=True).tolist(),
    }
    if name == WITH_MODEL[0]:
        other = sol.with_model(WITH_MODEL[1](model))
        v, e = other.eval_with_error(wi, wo)
        out["with_model"] = [v.tolist(), e.tolist()]
    return out


def compute() -> dict:
    return {name: outputs(name) for name in CASES}


def write(path: Path = PATH) -> None:
    """Atomically (a temporary file renamed into place)."""
    text = json.dumps(compute(), indent=1)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        f.write(text + "\n")
    os.replace(tmp, path)


if __name__ == "__main__":
    write()
    print(f"wrote {PATH}")
