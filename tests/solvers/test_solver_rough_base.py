"""Adding-doubling through a rough dielectric base under a smooth top (Solution.every_pair):
transmission down and up and reflection from below against PFMC (bsdflab.Layered), energy
conservation of a lossless stack from both sides, reciprocity with the index ratio, the
a-posteriori bound against a tight reference, and the base's own reflection from below.

Statistics (test_01). Each PFMC value v has a standard error s (independent walks per
pair; ``Layered.estimate``'s pooled error walks), the solver's value r its a-posteriori
bound e; a comparison passes when |v - r| <= z s + e. Both sides compare the light that
entered the stack (``scattered_only``: for reflection from below the base's own
reflection, the same exact evaluation in both, is left out; test_05 checks it apart).
Family: every (pair, wavelength) of every case and estimator plus one sqrt(pairs) x
mean-z test per case and estimator, alpha = 0.01 family-wise, Sidak-corrected (the family
counts the slow run's estimator too, conservative for the normal suite). Pairs: per case
3 of each kind (transmission down, transmission up, reflection from below), the first of
each kind grazing (86-88 degrees) on the viewer's or the light's side.

Power (test_02): the same comparison rejects the solver's answer with the eta^2 of the
transmission into water dropped, and reflection from below answered by the stack's
reflection from above (a transposed operator).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import bsdflab as bl
from bsdflab.optics.fresnel import fresnel_reflectance
from bsdflab.solvers import solve
from bsdflab.testing import sidak_significance, spherical_directions
from support.solver_pairs import assert_solver_matches_pfmc, pairs_by_kind, z_scores

WL = [450.0, 550.0, 650.0]
FAMILY_SIGNIFICANCE = 0.01
PER_KIND, SAMPLES = 3, 8000
KINDS = (("lower", "upper"), ("upper", "lower"), ("lower", "lower"))  # (wi, wo): down, up, below

HG = bl.Slab(2.0, sigma_a=0.1, sigma_s=0.5, phase={"type": "hg", "g": 0.6})
ISO = bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0)
CLEAR = bl.Slab(2.0, sigma_a=0.1, sigma_s=0.0)
FILM = [{"material": 1.38, "thickness_nm": 300.0}]
CASES = {
    # glass over water through a rough interface: a scattering slab
    "smooth 1.5 / HG slab / GGX 0.3 base to 1.33": lambda: bl.Layered(
        [bl.Dielectric(1.5, 1.0)], [HG], bl.RoughDielectric(0.3, 1.33, 1.5)
    ),
    # a coated plate, frosted below, in air: Beckmann, total internal reflection at the base
    "film top / iso slab / Beckmann 0.2 base to 1.0": lambda: bl.Layered(
        [bl.Dielectric(1.5, 1.0, film=FILM)], [ISO], bl.RoughDielectric(0.2, 1.0, 1.5, distribution="beckmann")
    ),
    # no scattering: the unscattered beam meets the base's lobe (transmission), and light
    # entering through the base returns by the top's specular reflection (from below)
    "smooth 1.5 / clear slab / GGX 0.5 base to 1.0": lambda: bl.Layered(
        [bl.Dielectric(1.5, 1.0)], [CLEAR], bl.RoughDielectric(0.5, 1.0, 1.5)
    ),
}
ESTIMATORS = ("pfmc2", pytest.param("pfmc", marks=pytest.mark.slow))
FAMILY = len(ESTIMATORS) * len(CASES) * (len(KINDS) * PER_KIND * len(WL) + 1)
Z_MAX = stats.norm.isf(sidak_significance(FAMILY_SIGNIFICANCE, FAMILY) / 2)


def pairs(seed):
    return pairs_by_kind(KINDS, PER_KIND, seed)


_ESTIMATES = {}


def estimate(name, estimator):
    """PFMC's estimate and the solver's answer (value, bound) of one case, scattered part
    (cached: test_02 reuses them)."""
    if (name, estimator) not in _ESTIMATES:
        m = CASES[name]()
        model = bl.Layered(list(m.interfaces), list(m.slabs), m.base, estimator=estimator)
        wi, wo = pairs(41)
        est = model.estimate(wi, wo, wavelengths=WL, samples=SAMPLES, seed=9, scattered_only=True)
        sol = solve(model, WL)
        assert sol.every_pair and not sol.two_sided
        _ESTIMATES[name, estimator] = (wi, wo, est, sol, *sol.eval_with_error(wi, wo, scattered_only=True))
    return _ESTIMATES[name, estimator]


@pytest.mark.parametrize("estimator", ESTIMATORS)
@pytest.mark.parametrize("name", list(CASES))
def test_01_rough_base_matches_pfmc(name, estimator):
    wi, wo, est, _, ref, ref_err = estimate(name, estimator)
    assert np.all(ref > 0)
    assert_solver_matches_pfmc(f"{name} [{estimator}]", wi, wo, WL, est, ref, ref_err, Z_MAX)


def test_02_mutations_fail():
    """Power: the comparison of test_01 rejects the solver's answer with the eta^2 of the
    transmission into water dropped, and reflection from below answered by the stack's
    reflection from above (mirrored pairs: a transposed operator)."""
    name = "smooth 1.5 / HG slab / GGX 0.3 base to 1.33"
    wi, wo, est, sol, ref, ref_err = estimate(name, "pfmc2")
    transmit = np.sign(wi[:, 2]) != np.sign(wo[:, 2])
    ratio = np.where(wi[:, 2] < 0, (1.0 / 1.33) ** 2, (1.33 / 1.0) ** 2)
    no_eta = np.where(transmit[:, None], ref * ratio[:, None], ref)
    z, _ = z_scores(est, no_eta, ref_err)
    print(f"eta^2 dropped: max z {np.max(z):.1f}")
    assert np.max(z) > 2 * Z_MAX, np.max(z)
    below = (wi[:, 2] < 0) & (wo[:, 2] < 0)
    flip = np.array([1.0, 1.0, -1.0])
    transposed = ref.copy()
    transposed[below] = sol.eval(wi[below] * flip, wo[below] * flip, scattered_only=True)
    z, _ = z_scores(est, transposed, ref_err)
    print(f"transposed operator: max z {np.max(z):.1f}")
    assert np.max(z) > 2 * Z_MAX, np.max(z)


def lossless(below_ior):
    slab = bl.Slab(5.0, sigma_a=0.0, sigma_s=3.0, phase={"type": "hg", "g": 0.5})  # tau 15
    return bl.Layered([bl.Dielectric(1.5, 1.0)], [slab], bl.RoughDielectric(0.3, below_ior, 1.5, multiscatter=True))


def hemisphere_integral(sol, light, h, n_mu, n_phi):
    """Integral of eval(wi, light) / |cos theta_light| over wi in the half-space of sign h:
    Gauss-Legendre in the outside cosine, the trapezoid rule in azimuth (periodic)."""
    x, w = np.polynomial.legendre.leggauss(n_mu)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    phi = 2.0 * np.pi * np.arange(n_phi) / n_phi
    t, p = np.meshgrid(np.arccos(mu), phi, indexing="ij")
    wi = spherical_directions(t.ravel(), p.ravel()) * np.array([1.0, 1.0, h])
    f_cos = sol.eval(wi, np.repeat(light, len(wi), axis=0)) / abs(light[0, 2])
    return (2.0 * np.pi / n_phi) * np.sum(np.repeat(w * mu, n_phi)[:, None] * f_cos, axis=0)


ALL_ANGLES = (0.0, 60.0, 80.0)


@pytest.mark.parametrize("below_ior, angles", [
    (1.0, (0.0, 80.0)), pytest.param(1.0, (60.0,), marks=pytest.mark.slow),
    pytest.param(1.33, ALL_ANGLES, marks=pytest.mark.slow), pytest.param(1.7, ALL_ANGLES, marks=pytest.mark.slow)])
def test_03_lossless_stack_conserves_energy_from_both_sides(below_ior, angles):
    """R + T = 1 for light from above and from below at 0, 60 and 80 degrees: from above the
    top's Fresnel reflection plus the scattered light leaving into both half-spaces; from
    below the whole eval (the rough base has no delta lobe: its own reflection is in eval)
    into both half-spaces. Quadrature: 48-node Gauss-Legendre in the outside cosine x 64
    azimuths per half-space (the base's lobes, alpha 0.3, and the scattered light are
    smooth in both). The slab is optically thick (tau 15: the unscattered beam is below
    1e-6), the base multiscatter (Kulla-Conty: a single-scattering rough dielectric loses
    10-25 % per bounce at alpha 0.3, which the many internal bounces compound). Tolerance
    3e-3: the base's own energy error (the same integral of the base alone, 128 x 256
    nodes: |1 - E| <= 1.1e-3), the quadrature's (the change from 32 x 48 to 64 x 96
    nodes was <= 8e-4, at 80 degrees from below, so 48 x 64's error is below it) and the
    solver's (its bound, <= 5e-3 relative on single pairs, far less on the integral),
    summed and rounded up; docs/solvers.md. One wavelength: nothing in this stack depends
    on it (non-dispersive indices, a grey lossless slab). Cost: 64 x 96 nodes at three
    wavelengths took 88 s for the base to 1.33 (its transmission pairs, through a narrow
    lobe, are the expensive ones; the cost is linear in pairs), 12 x the work of this.
    Mutation checked: Solution.eval scaling its transmission pairs by 1.05 fails it (by
    1.01 it passes: within the tolerance). Mutation: transmission pairs x 1.05 fails the
    CI case (base to 1.0: |R + T - 1| 1.3e-2 at normal incidence from above). Slow: the
    base to water (1.33, the same regime as 1.0, a base less dense than the slab, but
    through a narrow transmission lobe: ~75 CPU-s, 6 x the base to 1.0), and a base
    denser than the slab (1.7 below 1.5: total internal reflection at the base for
    light from below), max |R + T - 1| 8.7e-4. CI keeps one of the three (a third), at 0 and
    80 degrees (80: where the quadrature's error peaks); 60 degrees is slow (the cost is per
    light direction)."""
    sol = solve(lossless(below_ior), [550.0])
    worst = 0.0
    for side in (1.0, -1.0):
        for theta in np.radians(angles):
            light = spherical_directions(np.array([theta]), np.array([0.3])) * np.array([1, 1, side])
            total = fresnel_reflectance(np.cos(theta), 1.0, 1.5).unpolarised if side > 0 else 0.0
            for h in (1.0, -1.0):
                total = total + hemisphere_integral(sol, light, h, 48, 64)
            worst = max(worst, float(np.max(np.abs(total - 1.0))))
            assert np.max(np.abs(total - 1.0)) <= 3e-3, (side, np.degrees(theta), total)
    print(f"base to {below_ior}: max |R + T - 1| {worst:.1e}")


def test_04_reciprocity_with_the_index_ratio():
    """f(wi, wo) / n(wi)^2 = f(wo, wi) / n(wo)^2 (radiance transport; n of the medium each
    direction lies in), as test_solver_two_sided.py::test_04: for reflection from below the
    plain symmetry, for transmission between air and water the (1.33)^2 ratio. Tolerance
    1e-6 relative: the exit's and the entry's product integration are the same sums
    transposed, the unscattered beam's the base's own (reciprocal) BSDF. Both directions
    in one eval (a rough base's exits cost a set-up of ~5 s per call, not per pair: 12.0
    -> 8.2 CPU-s). Mutation: Solution.eval scaled by 1.02 where wi.z < 0 fails it."""
    sol = solve(CASES["smooth 1.5 / HG slab / GGX 0.3 base to 1.33"](), WL)
    wi, wo = pairs(5)
    both = sol.eval(np.concatenate([wi, wo]), np.concatenate([wo, wi]))
    f = both[:len(wi)] / np.abs(wo[:, 2:3])
    g = both[len(wi):] / np.abs(wi[:, 2:3])
    n_i = np.where(wi[:, 2] > 0, 1.0, 1.33)[:, None]
    n_o = np.where(wo[:, 2] > 0, 1.0, 1.33)[:, None]
    rel = np.abs(f / n_i**2 - g / n_o**2) / (f / n_i**2)
    print(f"reciprocity: max relative difference {np.max(rel):.1e}")
    assert np.max(rel) <= 1e-6, np.max(rel)


def test_05_the_base_own_reflection_from_below_is_exact():
    """eval - eval(scattered_only) is the base's own reflection from below (its BSDF, the
    part PFMC's scattered part leaves out too) and nothing for the other pairs. The
    scattered part is test_01's (``estimate``: the same solve's eval_with_error, whose value
    is eval(scattered_only=True)), so one eval here (~5 s a call: 12.0 -> 5.9 CPU-s).
    Mutation: Solution.eval scaled by 1.02 unless scattered_only fails it."""
    name = "smooth 1.5 / HG slab / GGX 0.3 base to 1.33"
    model = CASES[name]()
    wi, wo, _, sol, scattered, _ = estimate(name, "pfmc2")
    below = (wi[:, 2] < 0) & (wo[:, 2] < 0)
    assert below.sum() == PER_KIND
    diff = sol.eval(wi, wo) - scattered
    own = model.base.eval(wi, wo, wavelengths=WL)
    assert np.allclose(diff[below], own[below], rtol=1e-12, atol=0.0)
    assert np.all(diff[~below] == 0.0)


@pytest.mark.slow
def test_06_bound_covers_the_error():
    """eval_with_error's bound (the change to the coarser solve plus the change to a solve
    with the fine step doubled alone) is at least the actual error against a solve with
    every truncation tighter (32 nodes, 90 orders, 256 azimuth samples, fine step 0.05:
    the base's kernels then get 4 x the orders and 16 x the samples, sub-panels of 0.002
    rad), over the three kinds with grazing pairs, two wavelengths. Slow: the reference
    takes ~80 s per wavelength on the shared machine (cheaper references sit 4e-4 off it,
    as far as the solve under test)."""
    model = CASES["smooth 1.5 / HG slab / GGX 0.3 base to 1.33"]()
    wi, wo = pairs(11)
    value, bound = solve(model, [450.0, 650.0]).eval_with_error(wi, wo)
    ref = solve(model, [450.0, 650.0], nodes=32, orders=90, azimuth_samples=256, fine_step=0.05).eval(wi, wo)
    err = np.abs(value - ref)
    print(f"max error {np.max(err / ref):.1e} relative, max error / bound {np.max(err / bound):.3f}")
    assert np.all(err <= bound)
