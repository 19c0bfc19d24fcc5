"""bsdflab.fit's C++ forward model against independent references: the film part against
``tmm``, the non-scattering layered part against the coated-diffuse oracle (tmm optics and
adaptive quadrature), the thickness-spread average against brute-force averaging, and
closed-form identities. Every reference here is deterministic, so tolerances are round-off
or quadrature-error bounds (stated per test), not statistical."""
from __future__ import annotations

import numpy as np
import pytest
import tmm

from bsdflab.fit import GEOMETRIES, Dataset, ForwardModel, default_theta
from bsdflab.oracles import CoatedDiffuseOracle

SPEC, DIFF, TOT = (GEOMETRIES.index(g) for g in ("specular", "diffuse", "total"))


def design(rows) -> Dataset:
    r = np.array(rows, dtype=float)
    n = len(r)
    return Dataset(r[:, 0].astype(int), r[:, 1], r[:, 2], r[:, 3], np.zeros(n), np.ones(n))


def tmm_reflectance(n_list, d_list, theta, wl):
    return 0.5 * (tmm.coh_tmm("s", n_list, d_list, theta, wl)["R"] + tmm.coh_tmm("p", n_list, d_list, theta, wl)["R"])


@pytest.mark.parametrize("d, A, B", [(0.0, 1.83, 0.0), (120.0, 1.38, 0.0), (430.0, 1.83, 6000.0),
                                     (1150.0, 2.2, 12000.0)])
def test_specular_matches_tmm(d, A, B):
    wls, angles = [380.0, 455.0, 530.0, 640.0, 780.0], [0.0, 25.0, 55.0, 80.0, 89.0]
    ds = design([(SPEC, a, np.nan, w) for a in angles for w in wls])
    theta = default_theta(film_thickness_nm=d, film_ior=A, film_cauchy_b=B, substrate_ior=1.5515)
    got = ForwardModel(ds).evaluate(theta)
    n_e = theta[5]
    ref = [tmm_reflectance([n_e, A + B / w**2, 1.5515], [np.inf, d, np.inf], np.radians(a), w)
           for a in angles for w in wls]
    # both are exact Airy / transfer-matrix arithmetic: agreement to round-off
    np.testing.assert_allclose(got, ref, rtol=1e-11, atol=1e-14)


@pytest.mark.parametrize("d, sigma_a, rho, n_s", [(430.0, 0.3, 0.6, 1.5515), (250.0, 0.0, 1.0, 1.45),
                                                  (0.0, 1.2, 0.05, 1.6), (700.0, 0.05, 0.3, 1.33)])
def test_diffuse_and_total_match_the_coated_diffuse_oracle(d, sigma_a, rho, n_s):
    wls = [420.0, 550.0, 690.0]
    rows = [(DIFF, a, b, w) for a, b in [(0, 45), (30, -30), (60, 10), (85, 80)] for w in wls]
    rows += [(TOT, a, np.nan, w) for a in (0, 8, 50, 80) for w in wls]
    rows += [(SPEC, a, np.nan, w) for a in (8, 50) for w in wls]
    ds = design(rows)
    A, B = 1.83, 4000.0
    theta = default_theta(film_thickness_nm=d, film_ior=A, film_cauchy_b=B, substrate_ior=n_s,
                          pigment_absorption=sigma_a, slab_thickness_um=4.0, base_albedo=rho)
    got = ForwardModel(ds).evaluate(theta)
    oracles = {w: CoatedDiffuseOracle(
        int_ior=n_s, ext_ior=theta[5], thickness_um=4.0, sigma_a=sigma_a * (w / 550.0) ** -3.33, base_reflectance=rho,
        film=[{"material": {"type": "cauchy", "A": A, "B": B}, "thickness_nm": d}] if d else None) for w in wls}
    ref = []
    for g, a, b, w in rows:
        oracle = oracles[w]
        wi = np.array([[np.sin(np.radians(a)), 0.0, np.cos(np.radians(a))]])
        if g == DIFF:
            t = np.radians(abs(b))
            wo = np.array([[-np.sin(t), 0.0, np.cos(t)]])
            ref.append(np.pi * oracle.eval(wi, wo, [w])[0, 0] / np.cos(t))
        elif g == TOT:
            ref.append(oracle.specular_reflectance(wi, [w])[0, 0] + oracle.albedo(wi, [w])[0, 0])
        else:
            ref.append(oracle.specular_reflectance(wi, [w])[0, 0])
    # oracle: ~1e-13 (its docstring); ours: 32-node Gauss-Legendre, measured < 4e-15 vs 400 nodes
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-13)


def test_lossless_white_base_reflects_everything():
    """sigma_a = 0, rho = 1: total reflectance is exactly 1 (etendue identity)."""
    ds = design([(TOT, a, np.nan, w) for a in (0.0, 40.0, 75.0) for w in (400.0, 600.0)])
    theta = default_theta(film_thickness_nm=380.0, pigment_absorption=0.0, base_albedo=1.0)
    np.testing.assert_allclose(ForwardModel(ds).evaluate(theta), 1.0, atol=1e-12, rtol=0)


@pytest.mark.parametrize("mean, spread", [(430.0, 12.0), (700.0, 30.0)])
def test_thickness_spread_matches_brute_force_average(mean, spread):
    rows = [(SPEC, a, np.nan, w) for a in (10.0, 60.0) for w in (400.0, 520.0, 700.0)]
    rows += [(DIFF, 20.0, 50.0, w) for w in (450.0, 650.0)] + [(TOT, 8.0, np.nan, 500.0)]
    ds = design(rows)
    kw = dict(pigment_absorption=0.3, base_albedo=0.5)
    spread_model = ForwardModel(ds, thickness_nodes=24).evaluate(
        default_theta(film_thickness_nm=mean, film_thickness_spread_nm=spread, **kw))
    # brute force: the normal density on a fine grid over +-8 sd, each thickness exact
    d = np.linspace(mean - 8 * spread, mean + 8 * spread, 3201)
    w = np.exp(-0.5 * ((d - mean) / spread) ** 2)
    w /= w.sum()
    thetas = np.array([default_theta(film_thickness_nm=x, **kw) for x in d])
    brute = w @ ForwardModel(ds, thickness_nodes=1).evaluate(thetas)
    # 24-node Gauss-Hermite vs a 3201-point rule: GH is exact to ~1e-10 for phase spread
    # b = 4 pi n s / lambda < 1 and 2e-8 at b = 1.7 (700 +- 30 nm at 400 nm): far below any sigma
    np.testing.assert_allclose(spread_model, brute, rtol=0, atol=5e-8)
    # and the quadrature order matters (guards against a spread that is silently ignored)
    few = ForwardModel(ds, thickness_nodes=3).evaluate(
        default_theta(film_thickness_nm=mean, film_thickness_spread_nm=spread, **kw))
    assert np.max(np.abs(few - brute)) > 1e-6


def test_batch_rows_and_domain():
    ds = design([(SPEC, 30.0, np.nan, 500.0), (DIFF, 0.0, 40.0, 600.0)])
    m = ForwardModel(ds)
    good = default_theta()
    bad = [good.copy() for _ in range(4)]
    bad[0][0] = np.nan          # NaN thickness
    bad[1][4] = 0.9             # substrate index below the exterior's: outside the model
    bad[2][9] = 1.5             # albedo > 1
    bad[3][1] = -1.0            # negative spread
    out = m.evaluate(np.vstack([good, *bad, good]))
    assert np.all(np.isfinite(out[[0, 5]])) and np.all(np.isnan(out[1:5]))
    np.testing.assert_array_equal(out[0], out[5])            # deterministic, batch-independent
    np.testing.assert_array_equal(out[0], m.evaluate(good))
    with pytest.raises(ValueError, match="theta"):
        m.evaluate(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="thickness_nodes"):
        ForwardModel(ds, thickness_nodes=0)


def test_smooth_in_the_parameters():
    """No Monte Carlo inside: central differences converge like h^2 (a noisy model would not)."""
    ds = design([(SPEC, 30.0, np.nan, 500.0), (DIFF, 0.0, 40.0, 600.0), (TOT, 8.0, np.nan, 450.0)])
    m = ForwardModel(ds)
    base = default_theta(film_thickness_spread_nm=10.0, pigment_absorption=0.4, base_albedo=0.3)

    def deriv(h):
        e = np.zeros_like(base)
        e[0] = h
        return (m.evaluate(base + e) - m.evaluate(base - e)) / (2 * h)

    d1, d2, d3 = deriv(1.0), deriv(0.5), deriv(0.25)
    # Richardson: the h^2 error terms shrink 4x per halving
    np.testing.assert_allclose((d1 - d2) / (d2 - d3), 4.0, rtol=0.02)


def test_threads_do_not_change_the_answer(monkeypatch):
    """A large batch runs threaded; the result must equal the one-thread result bit for bit."""
    rows = [(SPEC, a, np.nan, w) for a in (10.0, 50.0) for w in np.arange(400.0, 701.0, 10.0)]
    rows += [(DIFF, 0.0, 45.0, w) for w in (450.0, 550.0, 650.0)]
    m = ForwardModel(design(rows))
    thetas = np.array([default_theta(film_thickness_nm=d, film_thickness_spread_nm=10.0, pigment_absorption=0.3,
                                     base_albedo=0.4) for d in np.linspace(300.0, 600.0, 64)])
    threaded = m.evaluate(thetas)
    monkeypatch.setenv("BSDFLAB_THREADS", "1")
    np.testing.assert_array_equal(m.evaluate(thetas), threaded)
