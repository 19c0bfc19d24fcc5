"""The fit's physical parameters: names, units, defaults (the xenopeltis preset's values)
and the column each takes in the C++ forward model (core/include/bsdflab/fit_forward.h).

``noise_scale`` is not a forward-model input: it multiplies every row's sigma in the
likelihood (1 = the stated uncertainties are right).

``FULL_PARAMETERS`` are used only by the full model (``[model] kind = "full"``, solved by
adding-doubling, bsdflab.fit.full_forward): the top's roughness, the slab's scattering, and
the iridophore platelet stack. The smooth model is the full one with roughness 0 (a smooth
top) and a non-scattering slab; ``SMOOTH_VALUES`` records that.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

from bsdflab import presets


@dataclass(frozen=True)
class Parameter:
    name: str
    unit: str
    default: float
    lo: float          # domain of the model (inclusive unless lo_open)
    hi: float
    description: str
    lo_open: bool = False


PARAMETERS: tuple[Parameter, ...] = (
    Parameter("film_thickness_nm", "nm", presets.FILM_THICKNESS_NM, 0.0, 20000.0,
              "mean thickness of the guanine (iridophore) film"),
    Parameter("film_thickness_spread_nm", "nm", 0.0, 0.0, 5000.0,
              "standard deviation of the film thickness across the measured spot"),
    Parameter("film_ior", "", presets.GUANINE_IOR, 0.0, 10.0,
              "film index, Cauchy A (n = A + B / lambda^2)", lo_open=True),
    Parameter("film_cauchy_b", "nm^2", 0.0, -1e6, 1e6, "film index, Cauchy B"),
    Parameter("substrate_ior", "", presets.KERATIN_IOR_550, 0.0, 10.0,
              "index of the slab under the film (keratin); must exceed exterior_ior",
              lo_open=True),
    Parameter("exterior_ior", "", presets.AIR_IOR, 0.0, 10.0, "index of the exterior (air)",
              lo_open=True),
    Parameter("pigment_absorption", "1/um", 1.2, 0.0, 1000.0, "slab absorption coefficient at 550 nm"),
    Parameter("absorption_exponent", "", 3.33, -20.0, 20.0,
              "sigma_a(lambda) = pigment_absorption (lambda / 550 nm)^-exponent (eumelanin 3.33)"),
    Parameter("slab_thickness_um", "um", 4.0, 0.0, 10000.0, "pigment slab thickness"),
    Parameter("base_albedo", "", 0.04, 0.0, 1.0, "Lambertian albedo of the base"),
)
FORWARD_NAMES = tuple(p.name for p in PARAMETERS)
NOISE = Parameter("noise_scale", "", 1.0, 0.0, 1000.0,
                  "multiplies every stated sigma in the likelihood", lo_open=True)
FULL_PARAMETERS: tuple[Parameter, ...] = (
    Parameter("roughness", "", presets.ROUGHNESS, 1e-3, 1.0,
              "microfacet alpha of the top (the adding-doubling solver's validated range)"),
    Parameter("sigma_s", "1/um", 0.2, 0.0, 1000.0, "slab scattering coefficient (grey)"),
    Parameter("hg_g", "", 0.6, -0.95, 0.95, "Henyey-Greenstein asymmetry of the slab's phase function"),
    Parameter("platelet_nm", "nm", 80.0, 0.0, 20000.0,
              "guanine platelet thickness of the iridophore stack (index: film_ior, B)"),
    Parameter("gap_nm", "nm", 100.0, 0.0, 20000.0, "cytoplasm gap between platelets"),
    Parameter("gap_ior", "", presets.CYTOPLASM_IOR, 0.0, 10.0, "index of the gaps (cytoplasm)",
              lo_open=True),
)
FULL_NAMES = tuple(p.name for p in FULL_PARAMETERS)
SMOOTH_VALUES = {"roughness": 0.0, "sigma_s": 0.0, "hg_g": 0.0}
ALL = {p.name: p for p in (*PARAMETERS, NOISE, *FULL_PARAMETERS)}
ALL_NAMES = tuple(ALL)


# Names before issue 30's single vocabulary (the presets', the page's and the exporters'
# names); still read, with a FutureWarning (shown by default, unlike DeprecationWarning).
RENAMED = {"film_index_A": "film_ior", "film_index_B": "film_cauchy_b", "sigma_a_550": "pigment_absorption",
           "substrate_index": "substrate_ior", "exterior_index": "exterior_ior", "gap_index": "gap_ior"}


def canonical(name: str, where: str = "") -> str:
    """``name``, or its new name (with a FutureWarning) if it is one of RENAMED's old names."""
    if name in RENAMED:
        warnings.warn(f"{where}parameter {name!r} is deprecated: it is now called {RENAMED[name]!r}",
                      FutureWarning, stacklevel=3)
        return RENAMED[name]
    return name


def parameter(name: str) -> Parameter:
    if name not in ALL:
        raise ValueError(f"unknown parameter {name!r}; known: {', '.join(ALL_NAMES)}")
    return ALL[name]


def in_domain(name: str, value: float) -> bool:
    p = parameter(name)
    above = value > p.lo if p.lo_open else value >= p.lo
    return bool(above and value <= p.hi)
