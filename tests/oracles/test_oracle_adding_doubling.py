"""The adding-doubling oracle against closed forms and the non-scattering oracle.

References, all independent of the adding-doubling code: Chandrasekhar's H-function of
a semi-infinite isotropic slab (solved below by its own fixed-point iteration, checked
by its exact zeroth moment), energy conservation, (generalised) reciprocity, the
single-scattering limit of a thin slab (closed form with the Henyey-Greenstein formula)
and CoatedDiffuseOracle (tmm + quadrature) for sigma_s = 0. Tolerances are the stated
accuracy of the oracle (module docstring: 1e-5 relative), loosened only where the
reference itself has a known truncation (the thin-slab limit, O(tau / mu)).
"""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab.oracles import AddingDoublingOracle, CoatedDiffuseOracle
from bsdflab.oracles._ad_slab import hg
from bsdflab.testing import random_unit_vectors, spherical_directions

WL = [450.0, 550.0, 650.0]


def h_function(omega: float, n: int = 200):
    """Chandrasekhar's H(mu) for isotropic scattering of albedo omega < 1, from
    1 / H(mu) = sqrt(1 - omega) + (omega / 2) int_0^1 mu' H(mu') / (mu + mu') dmu'
    (a contraction for omega < 1), on n Gauss-Legendre nodes, extended to any mu by the
    same equation (Nystrom)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x, w = 0.5 * (x + 1.0), 0.5 * w
    H = np.ones(n)
    root = np.sqrt(1.0 - omega)

    def step(mu, H):
        return 1.0 / (root + 0.5 * omega * np.sum(w * x * H / (mu[:, None] + x[None, :]), axis=1))

    for _ in range(10_000):
        H_next = step(x, H)
        if np.max(np.abs(H_next - H)) < 1e-15:
            break
        H = H_next
    moment = float(w @ H_next)
    return (lambda mu: step(np.atleast_1d(np.asarray(mu, dtype=float)), H_next)), moment


def pairs(cos_i, cos_o, dphi):
    """Direction pairs with the given cosines (sign = side) and azimuth difference."""
    wi = spherical_directions(np.arccos(np.abs(cos_i)), np.zeros_like(cos_i))
    wo = spherical_directions(np.arccos(np.abs(cos_o)), dphi)
    wi[:, 2] *= np.sign(cos_i)
    wo[:, 2] *= np.sign(cos_o)
    return wi, wo


@pytest.mark.parametrize("omega", [0.5, 0.9, 0.99])
def test_01_semi_infinite_isotropic_slab_matches_the_h_function(omega):
    """f = omega H(mu) H(mu0) / (4 pi (mu + mu0)) and plane albedo 1 - H(mu0) sqrt(1 - omega)
    (Chandrasekhar 1960, ch. IV) for an index-matched slab of optical depth 80."""
    H, moment = h_function(omega)
    assert moment == pytest.approx(2.0 / omega * (1.0 - np.sqrt(1.0 - omega)), abs=1e-13)
    oracle = AddingDoublingOracle(1.0, 1.0, [bl.Slab.from_albedo(80.0, omega, 1.0)], base_albedo=0.0)
    mu = np.array([1.0, 0.7, 0.3, 0.1, 0.02])
    ci, co = np.meshgrid(mu, mu)
    wi, wo = pairs(ci.ravel(), co.ravel(), np.full(ci.size, 1.3))
    value = oracle.eval(wi, wo, wavelengths=[550.0])[:, 0]
    ref = omega * H(ci.ravel()) * H(co.ravel()) / (4 * np.pi * (ci.ravel() + co.ravel())) * co.ravel()
    assert np.max(np.abs(value / ref - 1)) < 1e-5
    albedo = oracle.albedo(np.arccos(mu), wavelengths=[550.0])[:, 0]
    assert np.max(np.abs(albedo - (1 - H(mu) * np.sqrt(1 - omega)))) < 1e-6


PHASES = {"isotropic": None, "hg 0.6": {"type": "hg", "g": 0.6}, "hg -0.3": {"type": "hg", "g": -0.3}}


@pytest.mark.parametrize("phase", list(PHASES))
def test_02_lossless_stack_conserves_energy(phase):
    """Smooth 1.5 top, two lossless slabs (index-matched boundary between them), smooth
    base into water: every part of the balance from the oracle, summing to 1."""
    slabs = [bl.Slab(1.0, sigma_s=1.5, phase=PHASES[phase]), bl.Slab(0.5, sigma_s=2.0, phase=PHASES[phase])]
    oracle = AddingDoublingOracle(1.5, 1.0, slabs, base_ior=1.33)
    theta = np.radians([0.0, 30.0, 60.0, 80.0, 88.0])
    parts = oracle.energy(theta, wavelengths=[550.0])
    assert np.max(np.abs(parts["absorbed"])) < 1e-6, parts
    assert np.all(parts["reflection"] > 0.01) and np.all(parts["transmission"] > 0.01)
    # the delta part at normal incidence: Fresnel of the top plus the unscattered beam's
    # multiple reflections (exact geometric series)
    r1, r2 = 0.04, ((1.5 - 1.33) / (1.5 + 1.33)) ** 2
    a = np.exp(-2 * (1.5 + 1.0))
    assert parts["delta_reflection"][0, 0] == pytest.approx(r1 + (1 - r1) ** 2 * r2 * a / (1 - r1 * r2 * a), rel=1e-12)
    expected = (1 - r1) * (1 - r2) * np.sqrt(a) / (1 - r1 * r2 * a)
    assert parts["delta_transmission"][0, 0] == pytest.approx(expected, rel=1e-12)


def test_03_energy_balance_agrees_with_the_integral_of_eval():
    """albedo (node quadrature inside the slab) = the integral of eval over the exterior
    hemisphere by an independent Gauss-Legendre product rule in (cos theta_o, phi_o)."""
    oracle = AddingDoublingOracle(1.5, 1.0, [bl.Slab(2.0, sigma_a=0.1, sigma_s=1.0, phase=PHASES["hg 0.6"])],
                                  base_albedo=0.6)
    x, w = np.polynomial.legendre.leggauss(24)
    c, wc = 0.5 * (x + 1.0), 0.5 * w                      # cos theta_o in (0, 1)
    phi = 2 * np.pi * np.arange(32) / 32                  # periodic: trapezoid is spectral
    cc, pp = np.meshgrid(c, phi, indexing="ij")
    wo = spherical_directions(np.arccos(cc.ravel()), pp.ravel())
    theta_i = np.radians(40.0)
    value = oracle.eval(spherical_directions(theta_i, 0.0), wo, wavelengths=[550.0])[:, 0]
    # eval includes cos theta_o: the albedo is int eval d omega_o = int dc dphi eval
    integral = np.sum(value.reshape(cc.shape) * wc[:, None]) * (2 * np.pi / 32)
    assert integral == pytest.approx(oracle.albedo([theta_i], wavelengths=[550.0])[0, 0], rel=1e-5)


def test_04_reflection_is_reciprocal_and_transmission_generalised_reciprocal():
    """All six evaluations in one call: each call solves the stack with its query cosines
    (Nystrom: they never feed back into the nodes), and the six share the same 24 cosines,
    so one call costs what each of the six did. Mutation checked: the oracle's downward
    transmission 1e-4 relative high fails it."""
    slabs = [bl.Slab(1.0, sigma_a=0.2, sigma_s=2.0, phase=PHASES["hg 0.6"])]
    oracle = AddingDoublingOracle(1.5, 1.0, slabs, base_ior=1.2)
    wi = random_unit_vectors(12, seed=5, hemisphere="upper")
    wo = random_unit_vectors(12, seed=6, hemisphere="upper")
    below = -wo
    # (light leaves toward, arrives from): reflection both ways, transmission down and up,
    # reflection below both ways
    calls = [(wi, wo), (wo, wi), (below, wi), (wi, below), (-wi, below), (below, -wi)]
    values = oracle.eval(np.concatenate([a for a, _ in calls]), np.concatenate([b for _, b in calls]),
                         wavelengths=[550.0])[:, 0].reshape(len(calls), -1)
    f_io, f_oi = values[0] / wo[:, 2], values[1] / wi[:, 2]
    assert np.allclose(f_io, f_oi, rtol=1e-9)
    # radiance transport: f(wi <- wo) / n(wi)^2 = f(wo <- wi) / n(wo)^2
    t_down, t_up = values[2] / wi[:, 2], values[3] / wo[:, 2]
    assert np.all(t_up > 0)
    assert np.allclose(t_down / 1.2 ** 2, t_up / 1.0 ** 2, rtol=1e-9)
    r_below = values[4] / wo[:, 2]   # both below
    assert np.all(r_below > 0)
    assert np.allclose(r_below, values[5] / wi[:, 2], rtol=1e-9)


@pytest.mark.parametrize("phase", list(PHASES))
def test_05_thin_slab_is_single_scattering(phase):
    """tau = 1e-5, index-matched: f = omega p(Theta) (1 - exp(-tau (1/mu + 1/mu0))) / (mu + mu0)
    in reflection; double scattering is O(tau / mu) relative, ~1e-4 here."""
    tau, omega = 1e-5, 0.8
    g = 0.0 if PHASES[phase] is None else PHASES[phase]["g"]
    oracle = AddingDoublingOracle(1.0, 1.0, [bl.Slab.from_albedo(tau, omega, 1.0, PHASES[phase])])
    rng = np.random.default_rng(7)
    ci, co = rng.uniform(0.2, 1.0, 16), rng.uniform(0.2, 1.0, 16)
    wi, wo = pairs(ci, co, rng.uniform(0, 2 * np.pi, 16))
    value = oracle.eval(wi, wo, wavelengths=[550.0])[:, 0] / co
    cos_theta = np.sum(wi * -wo, axis=1)   # between the propagation directions -wo and wi
    ref = omega * hg(cos_theta, g) * -np.expm1(-tau * (1 / ci + 1 / co)) / (ci + co)
    assert np.max(np.abs(value / ref - 1)) < 1e-4


@pytest.mark.parametrize("sigma_a", [0.0, 0.3, 2.0])
def test_06_non_scattering_limit_matches_coated_diffuse_oracle(sigma_a):
    cdo = CoatedDiffuseOracle(int_ior=1.5, ext_ior=1.0, thickness_um=1.0, sigma_a=sigma_a, base_reflectance=0.7)
    ado = AddingDoublingOracle(1.5, 1.0, [bl.Slab(1.0, sigma_a=sigma_a)], base_albedo=0.7)
    wi = random_unit_vectors(40, seed=8, hemisphere="upper")
    wo = random_unit_vectors(40, seed=9, hemisphere="upper")
    assert np.allclose(ado.eval(wi, wo, wavelengths=WL), cdo.eval(wi, wo, wavelengths=WL), rtol=1e-6, atol=0)
    theta = np.radians([0.0, 45.0, 85.0])
    assert np.allclose(ado.albedo(theta, wavelengths=WL),
                       cdo.albedo(spherical_directions(theta, 0.0), wavelengths=WL), rtol=1e-6)
    assert np.allclose(ado.delta_reflectance(wi, wavelengths=WL), cdo.specular_reflectance(wi, wavelengths=WL),
                       rtol=1e-12)


def test_07_stated_accuracy_holds_at_the_hardest_settings():
    """Defaults vs a run with 4/3 the nodes (32), 60 orders and a 16x thinner start:
    relative change <= 1e-5 (the docstring's claim) for forward HG at high albedo,
    grazing included; eval_with_error bounds that change. The reference at 32 nodes lies
    within 1.1e-9 relative of one at 48 (twice the nodes, 1.3 against 7.7 CPU-s), 1/140
    of the change measured (1.6e-7; change / bound 0.070 either way). Mutation: the
    oracle's eval_with_error value scaled by 1 + 2e-5 fails it."""
    slabs = [bl.Slab.from_albedo(5.0, 0.99, 1.0, PHASES["hg 0.6"])]
    oracle = AddingDoublingOracle(1.5, 1.0, slabs, base_albedo=0.5)
    fine = AddingDoublingOracle(1.5, 1.0, slabs, base_albedo=0.5, nodes=4 * oracle.nodes // 3,
                                orders=60, thin_depth=oracle.thin_depth / 16)
    wi, wo = pairs(np.array([1.0, 0.5, 0.05, 0.02, 0.3]), np.array([0.02, 0.5, 0.05, 0.9, 0.3]),
                   np.array([0.0, 2.0, 3.1, 1.0, 0.2]))
    value, err = oracle.eval_with_error(wi, wo, wavelengths=[550.0])
    best = fine.eval(wi, wo, wavelengths=[550.0])
    assert np.max(np.abs(value / best - 1)) < 1e-5
    assert np.all(np.abs(value - best) <= err + 1e-15)


def test_08_from_layered_and_round_trip():
    m = bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.5, 1.5)],
                   [bl.Slab(1.0, sigma_s=1.0), bl.Slab(0.5, sigma_a=0.1, sigma_s=2.0, phase={"type": "hg", "g": 0.3})],
                   bl.Dielectric(1.0, 1.5))
    oracle = AddingDoublingOracle.from_layered(m)
    assert oracle.base_ior == 1.0 and len(oracle.slabs) == 2
    back = AddingDoublingOracle.from_dict(oracle.to_dict())
    wi = random_unit_vectors(5, seed=1)
    wo = random_unit_vectors(5, seed=2)
    assert np.array_equal(back.eval(wi, wo, wavelengths=[500.0]), oracle.eval(wi, wo, wavelengths=[500.0]))
    with pytest.raises(ValueError, match="index-matched"):
        AddingDoublingOracle.from_layered(bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.3, 1.5)],
                                                     [bl.Slab(1.0), bl.Slab(1.0)], bl.Diffuse(0.5)))


@pytest.mark.parametrize("kwargs, match", [
    ({"slabs": [{"thickness_um": 1.0, "phase": {"type": "vmf", "kappa": 2.0}}]}, "phase"),
    ({"slabs": [bl.Slab(1.0)], "base_albedo": 0.5, "base_ior": 1.0}, "not both"),
    ({"slabs": [bl.Slab(1.0)], "nodes": 2}, "nodes"),
    ({"slabs": []}, "slabs"),
    ({"slabs": [bl.Slab(1.0)], "base_albedo": 1.5}, "base_albedo"),
])
def test_09_bad_parameters_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        AddingDoublingOracle(1.5, 1.0, **kwargs)


def test_10_degenerate_directions_give_zero_not_nan():
    oracle = AddingDoublingOracle(1.5, 1.0, [bl.Slab(1.0, sigma_s=1.0)], base_albedo=0.5)
    wi = np.array([[0, 0, 1.0], [1.0, 0, 0], [0, 0, 1.0], [0, 0, -1.0]])
    wo = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, 0, -1.0], [0, 0, 1.0]])
    value = oracle.eval(wi, wo, wavelengths=WL)
    assert np.all(np.isfinite(value)) and np.all(value == 0.0)


def test_11_rgb_output_is_the_spectral_result_through_the_colour_weights():
    from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights
    oracle = AddingDoublingOracle(1.5, 1.0, [bl.Slab(1.0, sigma_a={"type": "rgb", "rgb": [0.1, 0.3, 0.9]},
                                                     sigma_s=1.0)], base_albedo=0.6)
    wi, wo = random_unit_vectors(3, seed=3, hemisphere="upper"), random_unit_vectors(3, seed=4, hemisphere="upper")
    spectral = oracle.eval(wi, wo, wavelengths=DEFAULT_WAVELENGTHS)
    assert np.allclose(oracle.eval(wi, wo), spectral @ srgb_weights(DEFAULT_WAVELENGTHS).T, rtol=1e-12)
