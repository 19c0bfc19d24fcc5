"""A structure layer's thickness spread (bsdflab.fit.thickness_spread) against an
independent computation: tmm's reflectance averaged over the thickness's normal distribution
by a fine trapezoid rule (121 points over +-8 sd: the Gaussian's truncation 1e-15; the rule's
error for a harmonic exp(i c x) of the integrand is its alias, exp(-(2 pi / h - c)^2 / 2) with
step h = 0.133 sd, below 1e-300 for the c < 20 of the harmonics that carry weight here: far
below round-off, as with the 401 points it used before, at a third of tmm's calls), in numpy.

The tolerance is derived per row, not measured: R(d) of one film is periodic in d with period
L = lambda / (2 n cos theta_t), so its Gaussian mean is the sum of its Fourier harmonics a_m
(computed here from tmm over one period, 64 points, FFT) damped by exp(-(m w s)^2 / 2),
w = 2 pi / L; the K Gauss-Hermite nodes damp harmonic m with the error
e_K(c) = |sum_k w_k exp(i c sqrt(2) x_k) / sqrt(pi) - exp(-c^2 / 2)|, c = m w s, so the model
is within sum_m |a_m| e_K(m w s) (+ 1e-12 round-off) of the truth.
"""
from __future__ import annotations

import numpy as np
import pytest
import tmm

from bsdflab.fit.data import Dataset
from bsdflab.fit.full_stack_config import FullStackConfig
from bsdflab.fit.stack_config import StackConfig
from bsdflab.fit.stack_forward import StackForward
from bsdflab.fit.structure import Structure
from bsdflab.fit.thickness_spread import THICKNESS_NODES

N_FILM, N_SUB = 1.83, 1.55
FINE = np.linspace(-8.0, 8.0, 121)                       # the reference's thickness offsets, in sd
FINE_W = np.exp(-0.5 * FINE**2) * np.r_[0.5, np.ones(119), 0.5]
FINE_W /= FINE_W.sum()


def specular(angles, wavelengths) -> Dataset:
    n = len(angles) * len(wavelengths)
    return Dataset(np.zeros(n, int), np.repeat(np.asarray(angles, float), len(wavelengths)), np.full(n, np.nan),
                   np.tile(np.asarray(wavelengths, float), len(angles)), np.zeros(n), np.ones(n))


def film(spread=None, thickness=430.0) -> Structure:
    layer = {"name": "film", "material": {"n": N_FILM}, "thickness_nm": thickness}
    if spread is not None:
        layer["thickness_spread_nm"] = spread
    return Structure.parse({"exterior": {"n": 1.0}, "substrate": {"n": N_SUB}, "layers": [layer]})


def values(s: Structure, sets: int = 1, **kw):
    d = {p.name: p.default for p in s.parameters()} | kw
    return lambda name: np.broadcast_to(np.asarray(d[name], float), (sets,)).copy()


def r_tmm(d, angle, wl):
    return tmm.unpolarized_RT([1.0, N_FILM, N_SUB], [np.inf, d, np.inf], np.radians(angle), wl)["R"]


def gh_error(c, k=THICKNESS_NODES):
    x, w = np.polynomial.hermite.hermgauss(k)
    return np.abs(np.sum(w * np.exp(1j * np.multiply.outer(c, np.sqrt(2.0) * x)), axis=-1) / np.sqrt(np.pi)
                  - np.exp(-0.5 * np.asarray(c) ** 2))


def bound(mean, sd, angle, wl):
    """sum_m |a_m| e_K(m w sd) for one film (the module docstring)."""
    cos_t = np.sqrt(1.0 - (np.sin(np.radians(angle)) / N_FILM) ** 2)
    period = wl / (2.0 * N_FILM * cos_t)
    r = np.array([r_tmm(mean + period * j / 64, angle, wl) for j in range(64)])
    a = np.abs(np.fft.rfft(r)) / 64
    m = np.arange(len(a))
    return float(np.sum(a[1:] * 2 * gh_error(m[1:] * 2 * np.pi / period * sd))) + 1e-12


ANGLES, WLS = [0.0, 45.0, 70.0], [350.0, 420.0, 530.0, 700.0]


@pytest.mark.parametrize("sd", [12.0, 25.0])
def test_spread_matches_tmm_fine_quadrature(sd):
    """A 430 nm film (n 1.83 on 1.55) with a spread of 12 and 25 nm at 3 angles x 4
    wavelengths: within the derived bound of tmm's fine average (measured 9.0e-10 against a
    largest bound of 1.9e-9 at 12 nm; 1.0e-5 against 1.2e-5 at 25 nm, where harmonic 2's c
    reaches 3.3 at 350 nm). The spread matters: it moves R by > 1e-2. Mutation caught: the
    nodes without the sqrt(2) (a spread too narrow by 1/sqrt(2)) fails every spread test."""
    s = film(sd)
    got = StackForward(specular(ANGLES, WLS), s).exact(values(s), [0.0], [0.0], [0.0])[0]
    ref, tol, sharp = [], [], []
    for a in ANGLES:
        for w in WLS:
            ref.append(FINE_W @ [r_tmm(430.0 + sd * x, a, w) for x in FINE])
            tol.append(bound(430.0, sd, a, w))
            sharp.append(r_tmm(430.0, a, w))
    err = np.abs(got - ref)
    assert np.all(err <= tol), (err.max(), err / tol)
    assert np.max(np.abs(np.array(sharp) - ref)) > 1e-2


def test_spread_composes_with_the_instrument():
    """Slit (FWHM 8 nm, the shared-grid path; and the Gauss-Hermite path at uneven
    wavelengths), cone (6 deg), angle offset, scale and background: the spread model against
    the same instrument's spread-free model (tested against tmm in test_fit_stack.py) averaged
    by the fine trapezoid over thickness, in numpy. Tolerance: the largest per-row bound at
    the nominal geometry, doubled (the instrument moves lambda and theta by < 3 %, which moves c
    alike). Mutation caught: the instrument arrays tiled instead of repeated per node (a
    set's nodes read the other set's instrument) misses by > 1e-2."""
    sd = 15.0
    s, sharp_s = film(sd), film()
    inst = dict(offset=[1.0, 0.0], acceptance=[6.0, 0.0], bandwidth=[8.0, 0.0])
    for wls in (np.arange(400.0, 461.0, 5.0), np.array([400.0, 433.0, 470.0, 525.0])):
        data = specular([20.0, 60.0], wls)
        f, g = StackForward(data, s), StackForward(data, sharp_s)
        v = values(s, 2, film_thickness_spread_nm=[sd, sd])
        got = f.evaluate(v, [0.9, 1.0], [0.01, 0.0], inst["offset"], inst["acceptance"], inst["bandwidth"])
        thick = 430.0 + sd * FINE
        sharp = values(sharp_s, len(FINE), film_thickness_nm=thick)
        ref = np.stack([FINE_W @ g.exact(sharp, np.full(len(FINE), inst["offset"][i]),
                                         np.full(len(FINE), inst["acceptance"][i]),
                                         np.full(len(FINE), inst["bandwidth"][i])) for i in range(2)])
        ref = np.array([[0.9], [1.0]]) * ref + np.array([[0.01], [0.0]])
        tol = 2 * max(bound(430.0, sd, a, w) for a in (20.0, 60.0) for w in wls)
        np.testing.assert_allclose(got, ref, rtol=0, atol=tol)


def test_periods_share_one_draw():
    """A periodic block's spread moves every period's layer together: against tmm with all
    three platelets at d + s x (fine trapezoid). Tolerance 1e-7, derived as above: a 3 nm
    spread over three 90 nm platelets (n 1.83) moves the round trip phase by c <= 3 x 4 pi
    1.83 x 3 / 400 = 0.52 per harmonic, and e_12(3 c) < 1e-9. Independent draws would differ
    by > 1e-4 (checked against their product rule in numpy)."""
    spec = {"exterior": {"n": 1.0}, "substrate": {"n": N_SUB}, "layers": [{"periods": 3, "layers": [
        {"name": "plate", "material": {"n": N_FILM}, "thickness_nm": 90.0, "thickness_spread_nm": 3.0},
        {"name": "gap", "material": {"n": 1.33}, "thickness_nm": 120.0}]}]}
    s = Structure.parse(spec)
    wls = [400.0, 550.0]
    got = StackForward(specular([30.0], wls), s).exact(values(s), [0.0], [0.0], [0.0])[0]

    def r(ds, w):
        stack = [np.inf, *[x for d in ds for x in (d, 120.0)], np.inf]
        return tmm.unpolarized_RT([1.0, *[N_FILM, 1.33] * 3, N_SUB], stack, np.radians(30.0), w)["R"]
    ref = [FINE_W @ [r([90.0 + 3.0 * x] * 3, w) for x in FINE] for w in wls]
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-7)
    x, w = np.polynomial.hermite.hermgauss(12)
    indep = [sum(w[i] * w[j] * w[k] * r(90.0 + 3.0 * np.sqrt(2) * x[[i, j, k]], wl)
                 for i in range(12) for j in range(12) for k in range(12)) / np.pi**1.5 for wl in wls]
    assert np.max(np.abs(np.array(indep) - ref)) > 1e-4


def test_spread_zero_is_the_exact_model():
    """No key: the parameter does not exist and the forward model is unchanged; spread 0 in
    the whole batch takes the same path (bit-identical); a 0 beside a non-zero set goes through
    the nodes (all at one thickness, weights summing to 1): equal to round-off."""
    data = specular(ANGLES, WLS)
    plain, zero = film(), film(0.0)
    assert "film_thickness_spread_nm" not in [p.name for p in plain.parameters()]
    r = StackForward(data, plain).exact(values(plain), [0.0], [0.0], [0.0])
    assert np.array_equal(StackForward(data, zero).exact(values(zero), [0.0], [0.0], [0.0]), r)
    mixed = StackForward(data, zero).exact(values(zero, 2, film_thickness_spread_nm=[0.0, 10.0]),
                                           [0.0] * 2, [0.0] * 2, [0.0] * 2)
    np.testing.assert_allclose(mixed[0], r[0], rtol=0, atol=1e-15)
    assert np.max(np.abs(mixed[1] - r[0])) > 1e-3


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf"), "5", True, 2e4])
def test_bad_spread_names_the_field(bad):
    with pytest.raises(ValueError, match="thickness_spread_nm"):
        film(bad)


def toml(spread_fixed=None, kind=None) -> dict:
    d = {"structure": {"substrate": {"n": N_SUB}, "layers": [
        {"name": "film", "material": {"n": N_FILM}, "thickness_nm": 430.0, "thickness_spread_nm": 5.0}]},
        "parameters": {"film_thickness_nm": {"prior": "uniform", "low": 300.0, "high": 600.0}}}
    if spread_fixed is not None:
        d["parameters"]["film_thickness_spread_nm"] = spread_fixed
    return d


@pytest.mark.parametrize("bad", [-1.0, float("nan")])
def test_bad_fixed_spread_names_the_parameter(bad):
    with pytest.raises(ValueError, match="film_thickness_spread_nm"):
        StackConfig.parse(toml(bad))


def test_spread_is_a_parameter_with_a_prior():
    c = StackConfig.parse(toml({"prior": "uniform", "low": 0.0, "high": 40.0}))
    assert "film_thickness_spread_nm" in c.priors
    assert StackConfig.parse(toml()).fixed["film_thickness_spread_nm"] == 5.0
    with pytest.raises(ValueError, match="thickness_nodes"):
        StackConfig.parse(toml() | {"model": {"thickness_nodes": 0}})


def test_full_model_refuses_the_spread():
    d = toml()
    d["model"] = {"kind": "full"}
    d["structure"] |= {"slab": {"thickness_um": 4.0, "sigma_a": 0.1, "sigma_s": 0.2, "hg_g": 0.6},
                       "base": {"albedo": 0.3}}
    with pytest.raises(ValueError, match="film.*thickness_spread_nm.*full model"):
        FullStackConfig.parse(d)


def test_posterior_recovers_the_spread_from_tmm_data():
    """Data: tmm's reflectance averaged over a 430 +- 15 nm film (81-point trapezoid over
    +-8 sd: h = 0.2 sd, alias exp(-(31.4 - c)^2 / 2) for harmonic m's c = 0.9 m, round-off for
    the harmonics that matter) at 20 and 60 deg x 36 wavelengths, 0.002 noise, fixed seed. The
    fit (thickness, spread, film index free) puts each truth inside its 99.7 % interval (each
    misses with probability 0.003 for a calibrated posterior: 0.9 % for the three, fixed by
    the seed), and a sharp film (spread fixed at 0) cannot: its chi2/n at its best fit (the
    MAP, found as run_sampler finds it, without the chain) is > 2. The chain is 1500 steps
    (3000 before, 20 of the test's 23 CPU-s): at tau ~12.5 that is ~950 effective draws, so
    the 99.7 % interval's ends scatter by ~0.3 posterior sd (0.2 at 3000), against truths
    measured 0.36-0.65 interval widths (2-4 sd) inside the ends. Mutation: the spread's nodes
    without the sqrt(2) (thickness_spread) fails it at 1500 steps (spread interval [19.6, 22.8]
    nm against the truth 15)."""
    from bsdflab.fit.sampling import find_map, run_sampler
    from bsdflab.fit.stack_posterior import StackPosterior

    truth = {"film_thickness_nm": 430.0, "film_thickness_spread_nm": 15.0, "film_ior": 1.83}
    angles, wls = [20.0, 60.0], np.arange(380.0, 711.0, 9.5)
    fine = np.linspace(-8.0, 8.0, 81)
    w = np.exp(-0.5 * fine**2) * np.r_[0.5, np.ones(79), 0.5]
    w /= w.sum()
    y = np.array([w @ [r_tmm(430.0 + 15.0 * x, a, wl) for x in fine] for a in angles for wl in wls])
    rng = np.random.default_rng(11)
    data = specular(angles, wls)
    data = Dataset(data.geometry, data.angle_deg, data.angle_out_deg, data.wavelength_nm,
                   y + 0.002 * rng.standard_normal(len(y)), np.full(len(y), 0.002))

    def config(spread_prior):
        d = toml()
        d["structure"]["exterior"] = {"n": 1.0}
        d["parameters"] |= {"film_ior": {"prior": "normal", "mean": 1.8, "sd": 0.1},
                            "film_thickness_spread_nm": spread_prior}
        d["sampler"] = {"walkers": 8, "max_steps": 1500, "check_every": 250, "seed": 5}
        return StackConfig.parse(d)
    post = StackPosterior([data], config({"prior": "uniform", "low": 0.0, "high": 40.0}))
    run = run_sampler(post, post.config.sampler, progress=False)
    lo, hi = np.quantile(run.draws(), [0.0015, 0.9985], axis=0)
    for j, name in enumerate(run.names):
        assert lo[j] < truth[name] < hi[j], (name, lo[j], hi[j])
    sharp = StackPosterior([data], config(0.0))
    # the MAP run_sampler would start its chain from (same starts, same seed): no chain needed
    best = find_map(sharp, sharp.config.sampler.map_starts, np.random.default_rng(sharp.config.sampler.seed)).x
    m = sharp.predict(best[None, :])[0]
    assert np.mean(((data.reflectance - m) / 0.002) ** 2) > 2.0


def test_clamped_nodes_against_tmm():
    """A spread comparable to the thickness (d 5 nm, s 10 nm): the nodes below 0 nm are
    evaluated at 0 nm (the layer absent there; thickness_spread.py's "Clamping", which biases
    the mean thickness up by s phi(d/s) - d Phi(-d/s) = 3.1 nm here). Oracle: the same 12
    Gauss-Hermite weights over tmm at max(0, d + sqrt(2) s x_k), so the tolerance is the
    core's agreement with tmm (1e-12). Mutation caught: the clamp removed (negative
    thicknesses reach the core) misses by > 1e-3."""
    s = film(10.0, thickness=5.0)
    got = StackForward(specular(ANGLES, WLS), s).exact(values(s), [0.0], [0.0], [0.0])[0]
    x, w = np.polynomial.hermite.hermgauss(THICKNESS_NODES)
    nodes = np.maximum(0.0, 5.0 + np.sqrt(2.0) * 10.0 * x)
    assert np.sum(nodes == 0.0) >= 3
    ref = [w @ [r_tmm(d, a, wl) for d in nodes] / np.sqrt(np.pi) for a in ANGLES for wl in WLS]
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12)


def layers(count: int) -> dict:
    return {"substrate": {"n": N_SUB}, "layers": [
        {"name": f"l{i}", "material": {"n": N_FILM if i % 2 else 1.4}, "thickness_nm": 100.0,
         "thickness_spread_nm": 2.0} for i in range(count)]}


def test_spread_cost_is_capped():
    """Five layers with a spread at 12 nodes would be 12^5 = 248 832 sets per parameter set:
    the config refuses it naming thickness_nodes (fixing four spreads at 0 makes it 12 sets),
    and so does the forward model when the batch turns them on (before it builds any set)."""
    with pytest.raises(ValueError, match=r"thickness_nodes = 12 over the 5 layers.*248832"):
        StackConfig.parse({"structure": layers(5), "parameters": {"l0_thickness_nm": {
            "prior": "uniform", "low": 50.0, "high": 150.0}}})
    fixed = {f"l{i}_thickness_spread_nm": 0.0 for i in range(1, 5)}
    StackConfig.parse({"structure": layers(5), "parameters": {"l0_thickness_nm": {
        "prior": "uniform", "low": 50.0, "high": 150.0}, **fixed}})
    s = Structure.parse(layers(5))
    with pytest.raises(ValueError, match="thickness_nodes"):
        StackForward(specular([10.0], [500.0]), s).exact(values(s), [0.0], [0.0], [0.0])


def test_many_sets_are_evaluated_in_chunks(monkeypatch):
    """600 parameter sets x 12 nodes = 7200 thickness sets, each costing 2 angles x 3
    wavelengths x 7 slit nodes = 42 values, with CHUNK_VALUES lowered to 42 x 1000: the
    forward model sees at most 1000 sets a call (memory bounded whatever the caller's batch),
    and every set's value equals its own evaluation alone to round-off. Mutation caught: one
    call for the whole batch (7200 sets) fails the size assertion."""
    from bsdflab.fit import thickness_spread as ts

    monkeypatch.setattr(ts, "CHUNK_VALUES", 42 * 1000)
    s, data = film(15.0), specular([20.0, 60.0], [400.0, 433.0, 525.0])
    f = StackForward(data, s)
    sizes = []
    smeared = f._smeared

    def spy(value, offset, acceptance, bandwidth):
        sizes.append(len(offset))
        return smeared(value, offset, acceptance, bandwidth)
    monkeypatch.setattr(f, "_smeared", spy)
    thick = np.linspace(300.0, 500.0, 600)
    inst = [np.linspace(0.0, 1.0, 600), np.full(600, 3.0), np.zeros(600)]
    got = f.exact(values(s, 600, film_thickness_nm=thick), *inst)
    assert max(sizes) <= 1000 and sum(sizes) == 600 * THICKNESS_NODES
    for i in (0, 341, 599):
        one = f.exact(values(s, 1, film_thickness_nm=thick[i]), *[[a[i]] for a in inst])[0]
        np.testing.assert_allclose(got[i], one, rtol=0, atol=1e-15)
