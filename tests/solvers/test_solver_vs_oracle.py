"""The adding-doubling solver (bsdflab.solvers) against the independent numpy oracle
(bsdflab.oracles.AddingDoublingOracle) on smooth coats, and its own closed-form checks:
energy conservation of a lossless stack, reciprocity, the a-posteriori bound, bad input.

Tolerances. The oracle is accurate to ~1e-7 relative with its defaults (docs/oracles.md);
the solver's default truncations (16 nodes per panel, start depth 2^-12 with a
Richardson correction, orders to 1e-6) are measured in docs/solvers.md. The comparisons
are deterministic: a tolerance is a stated accuracy, not a statistic.
"""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.oracles import AddingDoublingOracle
from bsdflab.solvers import solve
from bsdflab.spectra import Spectrum
from bsdflab.testing import random_unit_vectors, spherical_directions

WL = [450.0, 550.0, 650.0]
RTOL_ORACLE = 2e-5


def slab(tau, albedos, phase=None, thickness=1.0):
    sigma_t = tau / thickness
    albedos = np.asarray(albedos, dtype=float)
    sigma_s = float(np.max(albedos)) * sigma_t
    sigma_a = sigma_s / albedos - sigma_s
    return bl.Slab(thickness, sigma_a=Spectrum.tabulated(WL, sigma_a), sigma_s=sigma_s, phase=phase)


FWD, BACK = {"type": "hg", "g": 0.6}, {"type": "hg", "g": -0.3}
TOP = bl.Dielectric(1.5, 1.0)
CASES = {
    "iso tau1 lambert": ([TOP], [slab(1.0, [0.5, 0.7, 0.9])], bl.Diffuse(0.5)),
    "hg.6 tau5 black": ([TOP], [slab(5.0, [0.9, 0.95, 0.99], FWD)], bl.Diffuse(0.0)),
    "hg-.3 tau.5 lambert": ([TOP], [slab(0.5, [0.5, 0.8, 0.95], BACK)], bl.Diffuse(0.8)),
    "two slabs, matched boundary": ([TOP, bl.Dielectric(1.5, 1.5)],
                                    [slab(1.0, [0.6, 0.9, 0.99], FWD), slab(2.0, [0.5, 0.8, 0.95], BACK)],
                                    bl.Diffuse(0.5)),
}


def pairs(n=24, seed=3):
    wi = random_unit_vectors(n, seed=seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=seed + 1, hemisphere="upper")
    graze = spherical_directions(np.radians([85.0, 88.0, 30.0, 89.0]), [0.0, 1.0, 2.0, 4.0])
    wi[:4], wo[4:8] = graze, graze
    return wi, wo


@pytest.mark.parametrize("name", list(CASES))
def test_01_matches_numpy_oracle_on_smooth_coats(name):
    model = bl.Layered(*CASES[name])
    wi, wo = pairs()
    ours = solve(model, WL).eval(wi, wo)
    ref = AddingDoublingOracle.from_layered(model).eval(wi, wo, wavelengths=WL)
    rel = np.max(np.abs(ours - ref) / ref)
    print(f"{name}: max relative difference {rel:.2e}")
    assert rel <= RTOL_ORACLE


def hemisphere_integral(solution, w, wavelengths, n_mu=64, n_phi=48):
    """int eval(w, v) d omega_v over the upper hemisphere (the albedo for light from w,
    by reciprocity), Gauss-Legendre in cos theta_v and the trapezoid rule in azimuth."""
    x, wx = np.polynomial.legendre.leggauss(n_mu)
    mu, wmu = 0.5 * (x + 1.0), 0.5 * wx
    phi = 2.0 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - M**2)
    v = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
    vals = solution.eval(np.repeat(w[None], len(v), axis=0), v).reshape(n_mu, n_phi, -1)
    return np.einsum("m,mpc->c", wmu, vals) * (2.0 * np.pi / n_phi)


@pytest.mark.parametrize("theta", [0.0, 60.0, 85.0])
def test_02_lossless_stack_conserves_energy(theta):
    """Smooth 1.5 top, a non-absorbing HG 0.6 slab (tau 2), a white Lambertian base: the
    top's Fresnel reflection plus the hemispherical integral of eval is 1."""
    lossless = bl.Slab(1.0, sigma_a=0.0, sigma_s=2.0, phase=FWD)
    model = bl.Layered([TOP], [lossless], bl.Diffuse(1.0))
    w = spherical_directions(np.radians([theta]), [0.0])[0]
    total = hemisphere_integral(solve(model, WL), w, WL) + model.delta_reflectance(w[None], WL)[0]
    print(f"theta {theta}: R + R_delta - 1 = {total - 1.0}")
    assert np.max(np.abs(total - 1.0)) <= 1e-5


def test_03_reciprocity_rough_film_coat():
    """The snake (GGX 0.08 guanine-film top, HG slab, diffuse base): f(wi, wo) = f(wo, wi)."""
    wi, wo = pairs(12, seed=7)
    sol = solve(bl.presets.preset("xenopeltis"), WL)
    a = sol.eval(wi, wo) / wo[:, 2:]
    b = sol.eval(wo, wi) / wi[:, 2:]
    rel = np.max(np.abs(a - b) / np.abs(a + b) * 2.0)
    print(f"max relative reciprocity error {rel:.2e}")
    assert rel <= 1e-3


def test_04_error_estimate_bounds_the_error():
    """eval_with_error's bound exceeds the actual error (against a 2x finer solve) for
    the snake's scattered part."""
    model = bl.presets.preset("xenopeltis")
    wi, wo = pairs(10, seed=9)
    value, bound = solve(model, WL).eval_with_error(wi, wo)
    ref = solve(model, WL, nodes=32).eval(wi, wo)
    err = np.abs(value - ref)
    print(f"max error / bound {np.max(err / np.maximum(bound, 1e-300)):.3f}")
    assert np.all(err <= bound + 1e-12 * np.abs(ref))


def test_05_bad_input():
    rough = lambda a: bl.Layered([bl.RoughDielectric(a, 1.5, 1.0)], [bl.Slab(1.0)], bl.Diffuse(0.5))  # noqa: E731
    with pytest.raises(ValueError, match=r"alpha must be in \[0.001, 1.0\]"):
        solve(rough(2.0))
    with pytest.raises(ValueError, match=r"alpha must be in \[0.001, 1.0\]"):
        solve(rough(5e-4))
    sharp = bl.Layered([TOP], [bl.Slab(1.0, sigma_s=1.0, phase={"type": "hg", "g": 0.97})], bl.Diffuse(0.5))
    with pytest.raises(ValueError, match=r"g must be in \[-0.95, 0.95\]"):
        solve(sharp)
    vmf = bl.Layered([TOP], [bl.Slab(1.0, sigma_s=1.0, phase={"type": "vmf", "kappa": 3.0})], bl.Diffuse(0.5))
    with pytest.raises(ValueError, match="phase must be one of"):
        solve(vmf)
    with pytest.raises(ValueError, match="Layered"):
        solve(bl.Diffuse(0.5))
    peaked = bl.Layered([TOP], [bl.Slab(1.0, sigma_s=1.0, phase={"type": "hg", "g": 0.9})], bl.Diffuse(0.5))
    with pytest.warns(UserWarning, match="nodes raised from 16 to 61"):
        sol = solve(peaked, WL)
    assert sol.settings.nodes == 61
