"""A structure for the full model: ``exterior | layers | substrate | slab | base``, the top's
film stack on a rough interface over a scattering slab and a base (docs/fit.md, "Structures
for the full model"). TOML, with ``[model] kind = "full"``:

    [structure]
    exterior = "air"
    substrate = "keratin"            # the slab's matrix: the top interface's inner medium
    [[structure.layers]]             # the top's film stack, as bsdflab.fit.structure
    name = "film"
    material = "guanine"
    thickness_nm = 400.0
    [structure.interface]
    roughness = 0.1                  # microfacet alpha of the top (parameter roughness)
    distribution = "ggx"             # or "beckmann" (a setting, not a parameter)
    [structure.slab]
    thickness_um = 4.0               # slab_thickness_um
    sigma_a = "eumelanin"            # a named material with k: pigment_absorption (1/um at 550 nm)
                                     # times its 4 pi k / lambda, normalised at 550 nm; "power":
                                     # pigment_absorption (lambda / 550)^-absorption_exponent
                                     # (the snake's); a number: grey, 1/um (pigment_absorption)
    pigment_absorption = 1.2         # with a named sigma_a or "power": its value at 550 nm
    absorption_exponent = 3.33       # with "power" only
    sigma_s = 0.2                    # 1/um, grey (sigma_s)
    hg_g = 0.6                       # Henyey-Greenstein asymmetry (hg_g)
    [structure.base]
    albedo = 0.04                    # Lambertian (base_albedo), or material = "keratin": a smooth
                                     # interface to a half-space of that material (light leaves)

The numbers are the defaults of the parameters named in brackets (the snake's and the
presets' names); ``[parameters]`` gives any of them a prior. The solver's interfaces take one
real index per medium: the exterior's, the substrate's and a base material's enter at
``REFERENCE_NM`` (550 nm); the film layers keep their full dispersion (Cauchy, or n + ik
tabulated at 5 nm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bsdflab.fit import parameters as P
from bsdflab.fit.config import DISTRIBUTIONS
from bsdflab.fit.material import SIGMA_A_GRID_NM
from bsdflab.fit.materials import NAMED, Material, material
from bsdflab.fit.stack_material import REFERENCE_NM, film_material, real_index
from bsdflab.fit.structure import Medium, Structure

SLAB_KEYS = ("thickness_um", "sigma_a", "pigment_absorption", "absorption_exponent", "sigma_s", "hg_g")
SLAB_PARAMETERS = {
    "thickness_um": "slab_thickness_um",
    "pigment_absorption": "pigment_absorption",
    "absorption_exponent": "absorption_exponent",
    "sigma_s": "sigma_s",
    "hg_g": "hg_g",
}
TOP_NAMES_FIXED = ("roughness",)  # besides the layers' and media's parameters


def _number(where: str, key: str, v, p: P.Parameter) -> float:
    ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    if not ok or not (v > p.lo if p.lo_open else v >= p.lo) or v > p.hi:
        raise ValueError(f"{where} {key} must be a number in [{p.lo:g}, {p.hi:g}], got {v!r}")
    return float(v)


def _table(where: str, d, known: tuple[str, ...]) -> dict:
    if not isinstance(d, dict):
        raise ValueError(f"{where} must be a table")
    unknown = set(d) - set(known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}; known: {', '.join(known)}")
    return d


@dataclass(frozen=True)
class FullStructure:
    top: Structure  # exterior | layers | substrate (the top's film stack)
    distribution: str
    sigma_a: str  # "power", "grey" or a named material with k
    defaults: dict[str, float]  # roughness, slab and base parameters
    base_material: Medium | None  # None: a Lambertian base (base_albedo)

    def parameters(self) -> tuple[P.Parameter, ...]:
        # the slab's matrix is lossless (its absorption is sigma_a): no substrate_k
        out = [p for p in self.top.parameters() if p.name != "substrate_k"]
        for name, value in self.defaults.items():
            p = P.ALL[name]
            out.append(P.Parameter(p.name, p.unit, value, p.lo, p.hi, p.description, p.lo_open))
        if self.base_material is not None:
            m = self.base_material
            out += [
                P.Parameter(
                    f"base_{c.key}", "", c.default, c.lo, c.hi, f"base: {c.description}", lo_open=c.key == "ior"
                )
                for c in m.material.coefficients()
                if c.key != "k"
            ]
        return tuple(out)

    def top_names(self) -> tuple[str, ...]:
        """Parameters of the top alone (the solver reuses what lies below when only these change)."""
        return (*TOP_NAMES_FIXED, *(p.name for p in self.top.parameters() if not p.name.startswith("substrate_")))

    def _real_index(self, m: Medium, v: dict, prefix: str) -> float:
        return real_index(m, v, prefix)

    def _film_material(self, m: Medium, v: dict) -> dict:
        return film_material(m, v)

    def sigma_a_values(self, v: dict) -> np.ndarray:
        """The slab's absorption coefficient (1/um) on SIGMA_A_GRID_NM."""
        wl = SIGMA_A_GRID_NM
        a = v["pigment_absorption"]
        if self.sigma_a == "grey":
            return np.full(len(wl), a)
        if self.sigma_a == "power":
            return a * (wl / REFERENCE_NM) ** -v["absorption_exponent"]
        m = NAMED[self.sigma_a]
        grid = np.append(wl, REFERENCE_NM)[None, :]
        shape = m.index({}, grid).imag[0] / grid[0]
        return a * shape[:-1] / shape[-1]

    def model_dict(self, v: dict, samples: int = 256) -> dict:
        """The ``Layered`` model dict (``bsdflab.from_dict``) of one parameter set ``v`` (name -> value)."""
        s = self.top
        n_ext = self._real_index(s.exterior, v, "exterior")
        n_sub = self._real_index(s.substrate, v, "substrate")
        film = [
            {"material": self._film_material(s.layers[i], v), "thickness_nm": v[f"{s.layers[i].name}_thickness_nm"]}
            for i in s.order
            if v[f"{s.layers[i].name}_thickness_nm"] > 0
        ]
        top = {
            "type": "roughdielectric",
            "int_ior": n_sub,
            "ext_ior": n_ext,
            "alpha": v["roughness"],
            "distribution": self.distribution,
            "film": film or None,
        }
        wl = SIGMA_A_GRID_NM
        slab = {
            "thickness_um": v["slab_thickness_um"],
            "sigma_a": {"type": "tabulated", "wavelengths": wl.tolist(), "values": self.sigma_a_values(v).tolist()},
            "sigma_s": v["sigma_s"],
            "phase": {"type": "hg", "g": v["hg_g"]},
        }
        if self.base_material is None:
            base = {"type": "diffuse", "reflectance": v["base_albedo"]}
        else:
            base = {"type": "dielectric", "int_ior": self._real_index(self.base_material, v, "base"), "ext_ior": n_sub}
        return {"type": "layered", "interfaces": [top], "slabs": [slab], "base": base, "samples": samples}

    @classmethod
    def parse(cls, d: dict) -> FullStructure:
        if not isinstance(d, dict):
            raise ValueError("[structure] must be a table")
        if "slab" not in d:
            raise ValueError(
                "[structure] slab: the full model ([model] kind = 'full') needs a [structure.slab] "
                "(thickness_um, sigma_a, sigma_s, hg_g) and a [structure.base]"
            )
        if "base" not in d:
            raise ValueError(
                "[structure] base: a slab needs a base below it ([structure.base] albedo = ... or material = ...)"
            )
        top = Structure.parse({k: v for k, v in d.items() if k not in ("slab", "base", "interface")})
        if top.spread_layers():
            name = top.layers[top.spread_layers()[0]].name
            raise ValueError(
                f"[structure] layer {name!r}: thickness_spread_nm is not part of the full model ([model] kind = "
                "'full'; its solver takes one thickness per layer): fit the spread with the smooth model"
            )
        if top.substrate.material.k or top.substrate.material.k_amp:
            raise ValueError(
                "[structure] substrate: the slab's matrix must be lossless (a number, {cauchy = [A, B]} "
                "or a named lossless material); its absorption is [structure.slab] sigma_a"
            )
        defaults: dict[str, float] = {}
        face = _table("[structure.interface]", d.get("interface", {}), ("roughness", "distribution"))
        rough = P.ALL["roughness"]
        defaults["roughness"] = _number(
            "[structure.interface]", "roughness", face.get("roughness", rough.default), rough
        )
        distribution = face.get("distribution", "ggx")
        if distribution not in DISTRIBUTIONS:
            raise ValueError(
                f"[structure.interface] distribution must be one of {', '.join(DISTRIBUTIONS)}, got {distribution!r}"
            )
        kind = _slab(d["slab"], defaults)
        base_material = _base(d["base"], defaults)
        out = cls(top, distribution, kind, defaults, base_material)
        names = [p.name for p in out.parameters()]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ValueError(f"[structure]: parameter name(s) {', '.join(twice)} arise twice (rename the layer)")
        return out


def _slab(d, defaults: dict) -> str:
    """[structure.slab]: its parameters' defaults into ``defaults``; the sigma_a kind."""
    slab = _table("[structure.slab]", d, SLAB_KEYS)
    if "sigma_a" not in slab:
        raise ValueError(
            '[structure.slab] sigma_a is missing: a named material with k (e.g. "eumelanin"), '
            '"power" or a number (1/um)'
        )
    spec = slab["sigma_a"]
    if isinstance(spec, str):
        if spec != "power" and not (spec in NAMED and NAMED[spec].k_amp + NAMED[spec].k > 0):
            absorbing = [n for n, m in NAMED.items() if m.k_amp + m.k > 0]
            raise ValueError(
                f"[structure.slab] sigma_a: unknown or non-absorbing material {spec!r}; "
                f'absorbing: {", ".join(absorbing)} (or "power" or a number, 1/um)'
            )
        kind, absorption = spec, slab.get("pigment_absorption", P.ALL["pigment_absorption"].default)
    else:
        if "pigment_absorption" in slab:
            raise ValueError("[structure.slab] give sigma_a as a number or pigment_absorption, not both")
        kind, absorption = "grey", spec
    if "absorption_exponent" in slab and kind != "power":
        raise ValueError('[structure.slab] absorption_exponent needs sigma_a = "power"')
    defaults["pigment_absorption"] = _number("[structure.slab]", "sigma_a", absorption, P.ALL["pigment_absorption"])
    if kind == "power":
        p = P.ALL["absorption_exponent"]
        defaults[p.name] = _number("[structure.slab]", p.name, slab.get(p.name, p.default), p)
    for key in ("thickness_um", "sigma_s", "hg_g"):
        p = P.ALL[SLAB_PARAMETERS[key]]
        defaults[p.name] = _number("[structure.slab]", key, slab.get(key, p.default), p)
    return kind


def _base(d, defaults: dict) -> Medium | None:
    """[structure.base]: a Lambertian albedo (into ``defaults``, None returned) or a lossless
    half-space's medium."""
    base = _table("[structure.base]", d, ("albedo", "material"))
    if ("albedo" in base) == ("material" in base):
        raise ValueError(
            "[structure.base] takes albedo (a Lambertian base) or material (a half-space "
            f"below a smooth interface), one of them; got keys {sorted(base)}"
        )
    if "albedo" in base:
        defaults["base_albedo"] = _number("[structure.base]", "albedo", base["albedo"], P.ALL["base_albedo"])
        return None
    m: Material = material("[structure.base] material", base["material"])
    if m.k or m.k_amp:
        raise ValueError("[structure.base] material must be lossless (a dielectric half-space)")
    return Medium("base", m)
