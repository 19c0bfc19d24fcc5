"""The instrument between the structure and the data (refnx's ``ReflectModel(structure,
scale, bkg, dq)``, Nelson & Prescott 2019, J. Appl. Cryst. 52:193):

    reported = scale_series * (R smeared by bandwidth and acceptance, at theta + offset) + background

| parameter          | unit | off | meaning |
|---|---|---|---|
| ``scale``          | —    | 1   | reflectance relative to the reference (against a white diffuse |
|                    |      |     | standard, the specular beam times an unknown factor); one per    |
|                    |      |     | dataset, or ``scale_per_series = true``: one per named series   |
|                    |      |     | (``Dataset.series``), else one per angle                         |
| ``background``     | —    | 0   | additive offset (stray light, dark-current residue) |
| ``angle_offset_deg`` | deg | 0  | goniometer zero / sample tilt, added to every nominal angle |
|                    |      |     | (gonio rows of the full model: the sample tilted, both        |
|                    |      |     | directions rotated; bsdflab.fit.gonio_instrument)              |
| ``bandwidth_nm``   | nm   | 0   | FWHM of the spectrometer's Gaussian slit function |
| ``acceptance_deg`` | deg  | 0   | half-angle of the illumination cone, averaged uniformly in solid angle |

TOML: ``[instrument]`` (one dataset) or ``[dataset.instrument]`` per ``[[dataset]]``; each
key a prior table (bsdflab.fit.priors) or a number (fixed); missing ones are off. The
smearing is done in the C++ core (core/include/bsdflab/fit_instrument.h) for specular rows;
on the full model's gonio rows by one solve and one eval of every quadrature node
(bsdflab.fit.gonio_instrument, the same nodes).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from bsdflab.fit.parameters import Parameter
from bsdflab.fit.priors import Prior

INSTRUMENT: tuple[Parameter, ...] = (
    Parameter("scale", "", 1.0, 0.0, 100.0, "reflectance relative to the reference standard", lo_open=True),
    Parameter("background", "", 0.0, -1.0, 1.0, "additive background"),
    Parameter("angle_offset_deg", "deg", 0.0, -20.0, 20.0, "added to every nominal incidence angle"),
    Parameter("bandwidth_nm", "nm", 0.0, 0.0, 100.0, "FWHM of the Gaussian spectral slit function"),
    Parameter("acceptance_deg", "deg", 0.0, 0.0, 20.0, "half-angle of the illumination cone"),
)
BY_NAME = {p.name: p for p in INSTRUMENT}


@dataclass(frozen=True)
class Instrument:
    """Priors and fixed values of one dataset's instrument (unprefixed names)."""

    priors: dict[str, Prior]
    fixed: dict[str, float]
    scale_per_series: bool = False

    @classmethod
    def parse(cls, section: str, d: dict) -> Instrument:
        if not isinstance(d, dict):
            raise ValueError(f"[{section}] must be a table")
        unknown = set(d) - set(BY_NAME) - {"scale_per_series"}
        if unknown:
            raise ValueError(f"[{section}]: unknown key(s) {', '.join(sorted(unknown))}; "
                             f"known: {', '.join(BY_NAME)}, scale_per_series")
        per = d.get("scale_per_series", False)
        if not isinstance(per, bool):
            raise ValueError(f"[{section}] scale_per_series must be true or false, got {per!r}")
        priors, fixed = {}, {}
        for p in INSTRUMENT:
            spec = d.get(p.name, p.default)
            if isinstance(spec, dict) and set(spec) == {"fixed"}:
                spec = spec["fixed"]
            if isinstance(spec, dict):
                priors[p.name] = Prior.make(f"{section}.{p.name}", spec)
                continue
            ok = isinstance(spec, (int, float)) and not isinstance(spec, bool) and math.isfinite(spec)
            if not ok or not in_domain(p, spec):
                raise ValueError(f"[{section}] {p.name} must be a prior table or a number in "
                                 f"[{p.lo:g}, {p.hi:g}], got {spec!r}")
            fixed[p.name] = float(spec)
        return cls(priors, fixed, per)


def in_domain(p: Parameter, value: float) -> bool:
    return bool((value > p.lo if p.lo_open else value >= p.lo) and value <= p.hi)
