"""A per-query film thickness is the top film's alone (estimator version 8): PFMC's
eval, sample and pdf of a stack queried at ``thickness_nm=T`` against the same stack made
with its top film at T explicitly (queried with thickness None), for a stack with a
filmed top and a filmed (transmissive) base and for one with a filmed interior interface.

The reference is independent of the query path: the film is written into the model, and
every other boundary keeps its own film because nobody asks it to change. eval (both
estimators) and sample's lobe means are z-tests from the stated standard errors, the two
estimates from independent seeds, Sidak-corrected over each test's family at a
family-wise alpha of 1e-3. T = 2 x the top's own total, so the query's film
(300 nm x 2.0) is the explicit one (600 nm) to the bit: pdf(), a fixed function of (seed,
wi, wo), is then compared exactly. Mutations run once: every boundary of the walk given the
query's film again (the semantics before version 8) fails eval (both estimators, z 6.6-10
against bounds 3.9-4.0 at 4000 walks), sample and pdf on both stacks; the base's sampling
alone on the query's film fails eval at 16 000 walks (z 5.2-8.1). The smooth stacks only
ever sample their non-top boundaries; the rough filmed base is read through eval and pdf
too, and the mutations that give it the query's film there pass on the smooth stacks and
fail on it: the direct reflection from below (estimate.cpp; eval z 106-434 against 4.03,
both estimators), the entry's pdf (sample.cpp pdf(); pdf inexact), strategy B's exit
through it (connect.cpp; eval z 4.4-4.7 against 4.03) and pdf's exit density through it
(sample_walk.cpp; pdf inexact)."""

from __future__ import annotations

from statistics import NormalDist

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.lobes import Lobe

WL = [450.0, 550.0, 650.0]
OWN_NM, T_NM = 300.0, 600.0  # the top film's own total and the queried one (exactly 2x)
ALPHA = 1e-3  # family-wise, per test


def top(thickness_nm: float) -> bl.Dielectric:
    return bl.Dielectric(1.5, 1.0, film=[{"material": 1.38, "thickness_nm": thickness_nm}])


def filmed_base(top_nm: float, **kw) -> bl.Layered:
    base = bl.Dielectric(1.0, 1.5, film=[{"material": 2.2, "thickness_nm": 200.0}])
    return bl.Layered([top(top_nm)], [bl.Slab(1.0, sigma_a=0.05, sigma_s=0.5)], base, **kw)


def filmed_interior(top_nm: float, **kw) -> bl.Layered:
    mid = bl.Dielectric(1.3, 1.5, film=[{"material": 2.2, "thickness_nm": 150.0}])
    slabs = [bl.Slab(0.5, sigma_a=0.05, sigma_s=0.5), bl.Slab(0.5, sigma_a=0.1, sigma_s=0.3)]
    return bl.Layered([top(top_nm), mid], slabs, bl.Diffuse(0.5), **kw)


def rough_filmed_base(top_nm: float, **kw) -> bl.Layered:
    """A rough filmed base: its film is read through eval and pdf too (the direct reflection
    from below, the entry from below, strategy B's exit through it, pdf's exit density),
    which the smooth stacks above never call (their non-top boundaries are only sampled)."""
    base = bl.RoughDielectric(0.3, 1.0, 1.5, film=[{"material": 2.2, "thickness_nm": 200.0}])
    return bl.Layered([top(top_nm)], [bl.Slab(1.0, sigma_a=0.05, sigma_s=0.5)], base, **kw)


STACKS = {"filmed base": filmed_base, "filmed interior": filmed_interior, "rough filmed base": rough_filmed_base}
TRANSMISSIVE = {"filmed base", "rough filmed base"}


def sidak_z(m: int) -> float:
    """The two-sided z bound of one of m tests at family-wise ALPHA (Sidak)."""
    return NormalDist().inv_cdf(1.0 - (1.0 - (1.0 - ALPHA) ** (1.0 / m)) / 2.0)


def direction(theta_deg: float, phi_deg: float, up: bool) -> np.ndarray:
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t) if up else -np.cos(t)])


def pairs(name: str) -> tuple[np.ndarray, np.ndarray]:
    """Reflection from above at three geometries; for the transmissive stack also
    transmission both ways and reflection from below."""
    wi = [direction(30, 0, True), direction(10, 0, True), direction(60, 0, True)]
    wo = [direction(40, 180, True), direction(20, 90, True), direction(55, 150, True)]
    if name in TRANSMISSIVE:
        wi += [direction(30, 0, True), direction(25, 0, False), direction(35, 0, False)]
        wo += [direction(20, 180, False), direction(40, 120, True), direction(30, 160, False)]
    return np.array(wi), np.array(wo)


EVAL_CI = {("pfmc2", "filmed base"), ("pfmc", "filmed interior"), ("pfmc", "rough filmed base")}


@pytest.mark.parametrize("estimator, name", [
    pytest.param(e, n, marks=() if (e, n) in EVAL_CI else pytest.mark.slow)
    for e in ("pfmc", "pfmc2") for n in STACKS])
def test_eval_at_a_thickness_is_the_model_with_that_top_film(name, estimator):
    """CI runs each stack with one estimator (EVAL_CI, 3 of 6, both estimators), the other
    3 are slow. Mutation: the queried thickness ignored (Layered.estimate dropping
    thickness_nm) fails it."""
    make = STACKS[name]
    queried, explicit = make(OWN_NM, estimator=estimator), make(T_NM, estimator=estimator)
    wi, wo = pairs(name)
    n = 16_000  # the base's sampling alone on the old film (a partial mutation) reads z 5.2-8.1
    got = queried.estimate(wi, wo, WL, samples=n, seed=1, thickness_nm=T_NM)
    ref = explicit.estimate(wi, wo, WL, samples=n, seed=2)
    assert got.nonfinite == ref.nonfinite == 0
    z = np.abs(got.value - ref.value) / np.hypot(got.stderr, ref.stderr)
    assert np.all(ref.stderr > 0) and np.all(z < sidak_z(z.size)), (z, got.value, ref.value)


@pytest.mark.parametrize("name", list(STACKS))
def test_sample_at_a_thickness_is_the_model_with_that_top_film(name):
    """sample()'s weights summed per lobe kind over N draws estimate the albedo split into
    glossy / delta reflection / transmission; both models from independent uniforms."""
    make = STACKS[name]
    queried, explicit = make(OWN_NM), make(T_NM)
    sides = [True, False] if name in TRANSMISSIVE else [True]
    kinds = [
        int(Lobe.GLOSSY_REFLECTION),
        int(Lobe.DELTA_REFLECTION),
        int(Lobe.GLOSSY_TRANSMISSION),
        int(Lobe.DELTA_TRANSMISSION),
    ]
    n, zs = 20_000, []
    for up in sides:
        wi = np.tile(direction(30, 0, up), (n, 1))
        a = queried.sample(wi, seed=11, wavelengths=WL, thickness_nm=T_NM)
        b = explicit.sample(wi, seed=12, wavelengths=WL)
        for kind in kinds:
            wa = np.where((np.asarray(a.lobe) == kind)[:, None], a.weight, 0.0)
            wb = np.where((np.asarray(b.lobe) == kind)[:, None], b.weight, 0.0)
            se = np.hypot(wa.std(axis=0, ddof=1), wb.std(axis=0, ddof=1)) / np.sqrt(n)
            diff = np.abs(wa.mean(axis=0) - wb.mean(axis=0))
            zs.extend(np.where(se > 0, diff / np.where(se > 0, se, 1.0), np.where(diff > 0, np.inf, 0.0)))
    zs = np.array(zs)
    assert np.all(zs < sidak_z(zs.size)), zs


@pytest.mark.parametrize("name", list(STACKS))
def test_pdf_at_a_thickness_is_the_model_with_that_top_film(name):
    make = STACKS[name]
    wi, wo = pairs(name)
    # 256 walks per pdf: the share of walks leaving toward wo then depends on every boundary
    # (at the default 1 walk it takes one of two values for these smooth stacks)
    got = make(OWN_NM, pdf_samples=256).pdf(wi, wo, thickness_nm=T_NM, wavelengths=WL)
    ref = make(T_NM, pdf_samples=256).pdf(wi, wo, wavelengths=WL)
    assert np.all(ref > 0)
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=0)


def test_the_tests_see_a_rescaled_base():
    """Power: the semantics before version 8 (the base's film scaled with the top's, here
    200 -> 400 nm) is far outside the eval test's bound on the filmed-base stack."""
    explicit = filmed_base(T_NM)
    old = bl.Layered(
        explicit.interfaces, explicit.slabs, bl.Dielectric(1.0, 1.5, film=[{"material": 2.2, "thickness_nm": 400.0}])
    )
    wi, wo = pairs("filmed base")
    a = explicit.estimate(wi, wo, WL, samples=4000, seed=2)
    b = old.estimate(wi, wo, WL, samples=4000, seed=3)
    z = np.abs(a.value - b.value) / np.hypot(a.stderr, b.stderr)
    assert z.max() > 3 * sidak_z(z.size), z
