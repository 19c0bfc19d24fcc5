"""A fitted parameter set as a bsdflab model dict (``bsdflab.from_dict``), which
``bsdflab render`` (in a scene file) and ``bsdflab tabulate --json`` accept.

The dict is the fit's material in the engine's terms: a dielectric top (exterior ->
substrate index), smooth for the smooth model or rough (microfacet ``roughness``) for the
full one, coated with the Cauchy film, the platelet stack or nothing; a slab with the
fitted melanin-like absorption (tabulated at 5 nm over the data's range, 350-1000 nm) and,
in the full model, Henyey-Greenstein scattering; a Lambertian base. The full model's
forward model solves exactly this dict's ``Layered`` model (bsdflab.fit.full_forward), so
the posterior-mean material.json is the model that was fitted. The thickness *spread* of
the smooth model has no counterpart in one BSDF (it is a spatial average): the dict
carries the mean thickness.
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.config import ModelSettings
from bsdflab.fit.data import MODEL_RANGE_NM
from bsdflab.fit.parameters import ALL_NAMES

SIGMA_A_GRID_NM = np.arange(MODEL_RANGE_NM[0], MODEL_RANGE_NM[1] + 2.5, 5.0)


def film_layers(v: dict, model: ModelSettings) -> list[dict] | None:
    """The top's film as the engine's layer list (None: no film)."""
    index = {"type": "cauchy", "A": v["film_ior"], "B": v["film_cauchy_b"]}
    if model.film == "single":
        return [{"material": index, "thickness_nm": v["film_thickness_nm"]}] if v["film_thickness_nm"] > 0 else None
    if model.film == "stack":
        layers = []
        for i in range(model.platelets):
            layers.append({"material": index, "thickness_nm": v["platelet_nm"]})
            if i + 1 < model.platelets:
                layers.append({"material": v["gap_ior"], "thickness_nm": v["gap_nm"]})
        return layers
    return None


def material_dict(values, samples: int = 256, model: ModelSettings | None = None) -> dict:
    """Layered model dict for one full parameter vector (ALL_NAMES order, or a dict) of the
    model ``model`` (None: the smooth one)."""
    model = model or ModelSettings()
    v = dict(zip(ALL_NAMES, map(float, values))) if not isinstance(values, dict) else values
    wl = SIGMA_A_GRID_NM
    sigma_a = v["pigment_absorption"] * (wl / 550.0) ** -v["absorption_exponent"]
    top = {"type": "dielectric", "int_ior": v["substrate_ior"], "ext_ior": v["exterior_ior"],
           "film": film_layers(v, model)}
    slab = {"thickness_um": v["slab_thickness_um"],
            "sigma_a": {"type": "tabulated", "wavelengths": wl.tolist(), "values": sigma_a.tolist()},
            "sigma_s": 0.0}
    if model.kind == "full":
        top = {**top, "type": "roughdielectric", "alpha": v["roughness"], "distribution": model.distribution}
        slab = {**slab, "sigma_s": v["sigma_s"], "phase": {"type": "hg", "g": v["hg_g"]}}
    return {"type": "layered", "interfaces": [top], "slabs": [slab],
            "base": {"type": "diffuse", "reflectance": v["base_albedo"]}, "samples": samples}
