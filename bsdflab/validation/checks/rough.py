"""Rough (GGX) interfaces: Mitsuba 3 query by query, chi-square from above and below,
white furnace (<= 1, single scattering), reciprocity of reflection."""
from __future__ import annotations

from bsdflab.bsdfs import RoughConductor, RoughDielectric
from bsdflab.validation.checks._common import (
    CHI2_TOLERANCE,
    FURNACE_TOLERANCE,
    chi2_outcome,
    furnace_outcome,
    reciprocity_outcome,
    register_mitsuba_cases,
)
from bsdflab.validation.checks.basic import MITSUBA_STATISTIC, MITSUBA_TOLERANCE
from bsdflab.validation.registry import REGISTRY, effort

ROUGH_MITSUBA_EFFORT = effort({"pairs": 200}, {"pairs": 1000}, {"pairs": 4000})


def _register():
    from bsdflab.reference.mitsuba_rough import rough_cases

    register_mitsuba_cases("rough", rough_cases(), "mitsuba_rough.compare_rough",
                           "Mitsuba 3 roughconductor / roughdielectric (GGX, visible normals)",
                           MITSUBA_TOLERANCE + "; samples compared through the mapping between the two codes' "
                           "visible-normal warps (reference/visible_normals.py), and each code's samples "
                           "evaluated by the other", ROUGH_MITSUBA_EFFORT, MITSUBA_STATISTIC)


_register()

# Gauss-Legendre order per cell axis for the expected counts. With 5, the transmission lobe
# near total internal reflection (theta_i = 120 deg) is integrated ~1e-3 too coarsely, which
# 4e6 samples detect (p = 2e-6 at the full level; p = 0.45 with 16, same samples).
QUADRATURE = 16
ROUGH_CHI2_TOLERANCE = CHI2_TOLERANCE + f"; pdf integrated per cell with {QUADRATURE}-point Gauss-Legendre"
SAMPLING = effort({"samples": 100_000}, {"samples": 1_000_000}, {"samples": 4_000_000})


@REGISTRY.check(name="rough/chi2/conductor-a0.3", family="rough", title="Rough conductor sampler follows its pdf",
                model="RoughConductor(0.3, eta=0.2, k=3.0)", reference="the model's own pdf",
                statistic="smallest p-value over theta_i = 0, 50, 85 deg", tolerance=ROUGH_CHI2_TOLERANCE,
                effort=SAMPLING, make_model=lambda: RoughConductor(0.3, eta=0.2, k=3.0), seed=11)
def _chi2_conductor(ctx):
    # constant indices: the direction sampler is the same GGX visible-normal warp for any
    # Fresnel term, and a measured metal's 81-channel core costs far more to build and run
    return chi2_outcome(ctx, (0.0, 50.0, 85.0), quadrature_order=QUADRATURE)


@REGISTRY.check(name="rough/chi2/dielectric-a0.3", family="rough",
                title="Rough dielectric sampler follows its pdf, from above and below",
                model="RoughDielectric(0.3, 1.5, 1.0)", reference="the model's own pdf",
                statistic="smallest p-value over theta_i = 20, 70, 120, 160 deg", tolerance=ROUGH_CHI2_TOLERANCE,
                effort=SAMPLING, make_model=lambda: RoughDielectric(0.3, 1.5, 1.0), seed=12)
def _chi2_dielectric(ctx):
    return chi2_outcome(ctx, (20.0, 70.0, 120.0, 160.0), quadrature_order=QUADRATURE)


@REGISTRY.check(name="rough/furnace/dielectric-a0.3", family="rough",
                title="Rough dielectric: two albedo estimators agree and stay <= 1",
                model="RoughDielectric(0.3, 1.5, 1.0)", reference="closed form bound: albedo <= 1",
                statistic="largest |z| of (uniform - sampled) and of any excess over 1",
                tolerance=FURNACE_TOLERANCE, effort=effort({"samples": 200_000}, {"samples": 1_000_000}),
                make_model=lambda: RoughDielectric(0.3, 1.5, 1.0), seed=13)
def _furnace_dielectric(ctx):
    return furnace_outcome(ctx, (0.0, 45.0, 80.0), None)


@REGISTRY.check(name="rough/reciprocity/conductor-a0.3", family="rough", title="Rough conductor is reciprocal",
                model="RoughConductor(0.3, material='Au')", reference="Helmholtz reciprocity f(wi,wo) = f(wo,wi)",
                statistic="max relative asymmetry over random upper-hemisphere pairs, 3 wavelengths",
                tolerance="1e-12: the model is deterministic and symmetric in closed form, so only "
                          "double-precision rounding of the two evaluation orders remains",
                effort=effort({"pairs": 2000}, {"pairs": 20000}), make_model=lambda: RoughConductor(0.3, material="Au"),
                seed=14)
def _reciprocity(ctx):
    return reciprocity_outcome(ctx, 1e-12)
