"""A fitted parameter set as a bsdflab model dict (``bsdflab.from_dict``), which
``bsdflab render`` (in a scene file) and ``bsdflab tabulate --json`` accept.

The dict is the fit's material in the engine's terms: a smooth dielectric top (exterior
-> substrate index) coated with the Cauchy film, a non-scattering slab with the fitted
melanin-like absorption (tabulated on 380-780 nm), a Lambertian base. The thickness
*spread* has no counterpart in one BSDF (it is a spatial average): the dict carries the
mean thickness, and the spread is recorded under ``"fit"`` in the study's material.json.
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.parameters import ALL_NAMES
from bsdflab.spectra import DEFAULT_WAVELENGTHS


def material_dict(values, samples: int = 256) -> dict:
    """Layered model dict for one full parameter vector (ALL_NAMES order, or a dict)."""
    v = dict(zip(ALL_NAMES, map(float, values))) if not isinstance(values, dict) else values
    wl = np.asarray(DEFAULT_WAVELENGTHS)
    sigma_a = v["sigma_a_550"] * (wl / 550.0) ** -v["absorption_exponent"]
    film = [{"material": {"model": "cauchy", "A": v["film_index_A"], "B": v["film_index_B"]},
             "thickness_nm": v["film_thickness_nm"]}] if v["film_thickness_nm"] > 0 else None
    return {
        "type": "layered",
        "interfaces": [{"type": "dielectric", "int_ior": v["substrate_index"], "ext_ior": v["exterior_index"],
                        "film": film}],
        "slabs": [{"thickness_um": v["slab_thickness_um"],
                   "sigma_a": {"type": "tabulated", "wavelengths": wl.tolist(), "values": sigma_a.tolist()},
                   "sigma_s": 0.0}],
        "base": {"type": "diffuse", "reflectance": v["base_albedo"]},
        "samples": samples,
    }
