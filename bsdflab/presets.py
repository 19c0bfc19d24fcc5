"""Ready-made materials for the sunbeam snake, *Xenopeltis unicolor*, with their sources.

The model (Padrón-Griffe et al., "A biologically-inspired appearance model for snake
skin", CEIG 2023, doi:10.2312/CEIG.20231143): iridophores in the outer epidermis act as a
thin film at the top interface; below it a dark pigment layer absorbs light on the way
down and back up; a diffuse base gives the natural dark colour.

Parameters and where they come from
-----------------------------------
* Outer medium: keratin, n = 1.532 + 5890 / lambda^2 (lambda in nm), Leertouwer, Wilts &
  Stavenga 2011 (Opt. Express 19:24061). An interface needs one real index to bend rays,
  so the slab *and* the film's substrate use keratin's value at 550 nm (1.5515, computed
  from KERATIN_CAUCHY): keratin's dispersion (n falls from 1.569 at 400 nm to 1.544 at
  700 nm) is not modelled, and the guanine film's index is constant too. The film's
  colours come from interference, whose phase 4 pi n d cos / lambda the ~1 % index change
  would shift by well under the spread of film thicknesses the paper sweeps.
* Iridophore film: guanine crystals, n ~ 1.83 (the value Padrón-Griffe et al. 2023 use); no measured
  film thickness exists for Xenopeltis -- the paper sweeps 300-1200 nm; we default to the
  400 nm of its public code. The stack variant uses guanine platelets of 80 nm (within
  the reported 50-100 nm) separated by 100 nm of cytoplasm (n 1.33).
* Surface roughness: GGX alpha 0.08 (assumption: glossy scales, as in the paper's rough
  dielectric thin-film plugin; no measured value).
* Pigment slab: eumelanin absorption follows mu_a ~ lambda^-3.33 (Jacques & McAuliffe 1991,
  as compiled by S. Jacques, "Optical properties of biological tissues", 2013); the
  magnitude (1.2/um at 550 nm over 4 um) and the weak forward scattering are assumptions
  chosen for a dark, slightly brown body colour.
* Base: dark brown diffuse albedo (linear sRGB 0.05, 0.035, 0.025), an assumption matching
  photographs of the snake's body colour.
"""
from __future__ import annotations

import inspect

import numpy as np

from bsdflab.bsdfs import Diffuse, RoughDielectric
from bsdflab.bsdfs.interface_term import MAX_FILM_LAYERS
from bsdflab.layered import Layered, Slab
from bsdflab.spectra import Spectrum
from bsdflab.util import args as check

KERATIN_CAUCHY = {"type": "cauchy", "A": 1.532, "B": 5890.0}
KERATIN_IOR_550 = KERATIN_CAUCHY["A"] + KERATIN_CAUCHY["B"] / 550.0**2
GUANINE_IOR = 1.83
CYTOPLASM_IOR = 1.33
AIR_IOR = 1.000277
FILM_THICKNESS_NM = 400.0
ROUGHNESS = 0.08
BASE_RGB = (0.05, 0.035, 0.025)


# A platelet and the gap below it are two film layers; the last platelet has no gap.
MAX_PLATELETS = (MAX_FILM_LAYERS + 1) // 2


def melanin_absorption(sigma_550: float = 1.2, exponent: float = 3.33) -> Spectrum:
    """sigma_a(lambda) = sigma_550 (lambda / 550 nm)^-exponent in 1/um, on 380-780 nm.

    sigma_550 in [0, 1e6] 1/um (the slab's range); exponent in [0, 10] (melanins: 2.5-4)."""
    sigma_550 = check.real_scalar("sigma_550", sigma_550, 0.0, 1e6)
    exponent = check.real_scalar("exponent", exponent, 0.0, 10.0)
    wl = np.linspace(380.0, 780.0, 81)
    values = sigma_550 * (wl / 550.0) ** -exponent
    check.real_array("sigma_a", values, 0.0, 1e6)  # the slab's range over the whole grid
    return Spectrum.tabulated(wl, values, name="sigma_a")


def guanine_film(thickness_nm: float = FILM_THICKNESS_NM, ior: float = GUANINE_IOR) -> list[dict]:
    """One film of ``thickness_nm`` in [0, 1e9] nm and index ``ior`` (guanine by default)."""
    return [{"material": check.real_scalar("ior", ior, 1e-3, 1e3),
             "thickness_nm": check.film_thickness("thickness_nm", thickness_nm)}]


def iridophore_stack(platelets: int = 5, platelet_nm: float = 80.0, gap_nm: float = 100.0) -> list[dict]:
    """Alternating guanine platelets and cytoplasm gaps (a multilayer reflector).

    platelets: an integer in [1, 16] (2 platelets - 1 layers fit the core's 32-layer film);
    platelet_nm, gap_nm: thicknesses in [0, 1e9] nm."""
    platelets = check.integer("platelets", platelets, 1, MAX_PLATELETS)
    platelet_nm = check.film_thickness("platelet_nm", platelet_nm)
    gap_nm = check.film_thickness("gap_nm", gap_nm)
    layers = []
    for i in range(platelets):
        layers.append({"material": GUANINE_IOR, "thickness_nm": platelet_nm})
        if i + 1 < platelets:
            layers.append({"material": CYTOPLASM_IOR, "thickness_nm": gap_nm})
    return layers


PIGMENT_SIGMA_550 = 1.2


def _top(film, roughness: float = ROUGHNESS) -> RoughDielectric:
    return RoughDielectric(roughness, int_ior=KERATIN_IOR_550, ext_ior=AIR_IOR, film=film)


def _pigment_slab(sigma_550: float = PIGMENT_SIGMA_550) -> Slab:
    return Slab(thickness_um=4.0, sigma_a=melanin_absorption(sigma_550), sigma_s=0.2,
                phase={"type": "hg", "g": 0.6})


# Keyword overrides (the lobe explorer's sliders and `preset(name, **overrides)`):
# film_ior: the iridophore film's index; roughness: GGX alpha of the top; pigment_absorption:
# the melanin slab's sigma_a at 550 nm in 1/um; base_albedo: linear-sRGB albedo of the base.
def xenopeltis(film_thickness_nm: float = FILM_THICKNESS_NM, samples: int = 256, seed: int = 0,
               film_ior: float = GUANINE_IOR, roughness: float = ROUGHNESS,
               pigment_absorption: float = PIGMENT_SIGMA_550, base_albedo=BASE_RGB) -> Layered:
    """The full model: guanine thin film on keratin, melanin slab, dark diffuse base."""
    return Layered([_top(guanine_film(film_thickness_nm, film_ior), roughness)], [_pigment_slab(pigment_absorption)],
                   Diffuse(base_albedo), samples=samples, seed=seed)


def xenopeltis_iridophore_stack(samples: int = 256, seed: int = 0, roughness: float = ROUGHNESS,
                                pigment_absorption: float = PIGMENT_SIGMA_550,
                                base_albedo=BASE_RGB) -> Layered:
    """As `xenopeltis` with a 5-platelet guanine/cytoplasm stack as the iridophore."""
    return Layered([_top(iridophore_stack(), roughness)], [_pigment_slab(pigment_absorption)],
                   Diffuse(base_albedo), samples=samples, seed=seed)


def xenopeltis_diffuse(base_albedo=BASE_RGB) -> Diffuse:
    """Ablation: the base colour alone (no film, no pigment slab, no gloss)."""
    return Diffuse(base_albedo)


def xenopeltis_thin_film(film_thickness_nm: float = FILM_THICKNESS_NM, samples: int = 256,
                         seed: int = 0, film_ior: float = GUANINE_IOR, roughness: float = ROUGHNESS,
                         base_albedo=BASE_RGB) -> Layered:
    """Ablation: the thin-film interface over the diffuse base, without the pigment slab."""
    return Layered([_top(guanine_film(film_thickness_nm, film_ior), roughness)], [Slab(thickness_um=0.0)],
                   Diffuse(base_albedo), samples=samples, seed=seed)


PRESETS = {
    "xenopeltis": xenopeltis,
    "xenopeltis-stack": xenopeltis_iridophore_stack,
    "xenopeltis-diffuse": xenopeltis_diffuse,
    "xenopeltis-thin-film": xenopeltis_thin_film,
}


def preset(name: str, **kwargs):
    """A preset by name (see PRESETS)."""
    if not isinstance(name, str) or name not in PRESETS:
        raise ValueError(f"unknown preset {check.brief(name)}; known presets: {', '.join(PRESETS)}")
    valid = preset_options(name)
    unknown = sorted(set(kwargs) - set(valid))
    if unknown:
        raise ValueError(f"preset {name!r} has no option {', '.join(map(repr, unknown))}; "
                         f"its options: {', '.join(valid) or 'none'}")
    return PRESETS[name](**kwargs)


def preset_options(name: str) -> list[str]:
    """The keyword options preset ``name`` takes (what a request's overrides may set)."""
    return list(inspect.signature(PRESETS[name]).parameters)
