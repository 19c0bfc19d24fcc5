"""Basic materials (Diffuse, Conductor, Dielectric): Mitsuba 3 query by query, chi-square,
white furnace, eval/pdf consistency."""
from __future__ import annotations

from bsdflab.bsdfs import Diffuse
from bsdflab.validation.checks._common import (
    CHI2_TOLERANCE,
    FURNACE_TOLERANCE,
    chi2_outcome,
    furnace_outcome,
    register_mitsuba_cases,
)
from bsdflab.validation.registry import REGISTRY, effort

MITSUBA_TOLERANCE = ("relative error 1e-5 on pairs float32 can resolve (Mitsuba computes in float32, "
                     "both codes get bit-identical float32 inputs and uniforms); pairs it cannot "
                     "(near the critical angle, grazing) within their own float32 error bound "
                     "(reference/conditioning.py); sRGB cases add the documented RGB->spectrum "
                     "round trip (<= 3e-4); every lobe choice and sample validity must agree")
MITSUBA_STATISTIC = ("largest error of eval, pdf, sample weight, direction, sample pdf and eta, in units "
                     "of its allowance (<= 1 passes)")
MITSUBA_EFFORT = effort({"pairs": 300}, {"pairs": 1000}, {"pairs": 4000})


def _register():
    from bsdflab.reference.mitsuba_bsdf import standard_cases

    register_mitsuba_cases("basic", standard_cases(), "mitsuba_bsdf.compare_bsdf",
                           "Mitsuba 3 (diffuse / conductor / dielectric / twosided)", MITSUBA_TOLERANCE,
                           MITSUBA_EFFORT, MITSUBA_STATISTIC)


_register()

SAMPLING = effort({"samples": 100_000}, {"samples": 1_000_000}, {"samples": 4_000_000})


@REGISTRY.check(name="basic/chi2/diffuse", family="basic", title="Diffuse sampler follows its pdf",
                model="Diffuse(0.5)", reference="the model's own pdf (chi-square goodness of fit)",
                statistic="smallest p-value over theta_i = 0, 45, 87 deg", tolerance=CHI2_TOLERANCE,
                effort=SAMPLING, make_model=lambda: Diffuse(0.5), seed=1)
def _chi2_diffuse(ctx):
    return chi2_outcome(ctx, (0.0, 45.0, 87.0))


@REGISTRY.check(name="basic/furnace/diffuse-white", family="basic", title="White Diffuse conserves energy",
                model="Diffuse(1.0)", reference="closed form: albedo = 1 at every angle",
                statistic="largest |z| of (uniform - sampled) and (estimate - 1)",
                tolerance=FURNACE_TOLERANCE, effort=effort({"samples": 200_000}, {"samples": 1_000_000}),
                make_model=lambda: Diffuse(1.0), seed=2)
def _furnace_diffuse(ctx):
    return furnace_outcome(ctx, (0.0, 30.0, 60.0, 85.0), 1.0)


@REGISTRY.check(name="basic/furnace/dielectric-glass", family="basic",
                title="Glass scatters all light (delta lobes)", model="Dielectric(1.5, 1.0)",
                reference="closed form: R + T = 1 (weights carry (n_i/n_t)^2 on transmission)",
                statistic="largest |z| of the mean sample weight's energy against 1",
                tolerance=FURNACE_TOLERANCE, effort=effort({"samples": 200_000}, {"samples": 1_000_000}),
                make_model=lambda: __import__("bsdflab").Dielectric(1.5, 1.0), seed=3)
def _furnace_glass(ctx):
    import numpy as np

    from bsdflab.lobes import Lobe
    from bsdflab.testing import spherical_directions
    from bsdflab.validation.registry import Outcome

    n = int(ctx.effort["samples"])
    worst, rows = 0.0, {}
    for k, theta in enumerate((0.0, 40.0, 80.0)):
        wi = spherical_directions(np.radians(theta), 0.0)
        s = ctx.model.sample(np.tile(wi, (n, 1)), seed=ctx.seed + k, wavelengths=[550.0])
        # transmitted weights carry (n_i/n_t)^2 (radiance); energy is weight / eta^2 there
        energy = np.where(s.lobe == int(Lobe.DELTA_TRANSMISSION), s.weight[:, 0] * s.eta**2, s.weight[:, 0])
        m, se = energy.mean(), energy.std(ddof=1) / np.sqrt(n)
        worst = max(worst, abs(m - 1.0) / max(se, 1e-12))
        rows[f"{theta:g} deg"] = m
    from bsdflab.validation.checks._common import z_limit

    z = z_limit(3)
    return Outcome(worst < z, worst, z, "<", f"largest |z| {worst:.2f}", {"energy": rows})
