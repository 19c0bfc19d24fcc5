"""Energy of rough interfaces: the single-scattering loss (measured), and the Kulla-Conty
multiple-scattering compensation (multiscatter=True): white furnace from both sides,
its tables' error, reciprocity, chi2 of the mixture sampler, and against the microsurface
random-walk oracle (Heitz et al. 2016)."""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.oracles import microsurface as ms
from bsdflab.testing import (
    albedo_sampled,
    albedo_uniform,
    bsdf_chi2,
    eval_pdf_consistency,
    random_unit_vectors,
    reciprocity_error,
)
from support.directions import directions_at

SIGNIFICANCE = 0.01
FILM = [{"material": 2.0, "thickness_nm": 400.0}]
# Tabulation error of the energy tables (rough_multiscatter.h: 33 nodes in sqrt(mu), a
# 64 x 64 cosine-spaced product rule over the visible-normal warp), measured: <= 1.5e-3.
TABLE_ERROR = 2e-3


def _unscaled_energy(bsdf, wi, n, seed):
    """Mean and standard error of sample weights with the radiance scaling of transmitted
    samples undone (weight * eta^2): the energy fraction scattered, R + T."""
    s = bsdf.sample(np.tile(wi, (n, 1)), seed=seed, wavelengths=[550.0])
    e = np.where(s.lobe == Lobe.GLOSSY_TRANSMISSION, s.weight[:, 0] * s.eta**2, s.weight[:, 0])
    return e.mean(), e.std() / np.sqrt(n)


@pytest.mark.parametrize("deg, expected", [(0, 0.900), (30, 0.871), (60, 0.781)])
def test_01_single_scattering_loses_10_to_22_percent_from_inside(deg, expected):
    """The issue's measurement: GGX alpha 0.3 at eta 1.5 seen from inside keeps only R + T
    = 0.900 / 0.871 / 0.781 (to the 3 digits quoted; 4.5 sigma + 5e-4 rounding)."""
    g = bl.RoughDielectric(0.3, 1.5, 1.0)
    mean, err = _unscaled_energy(g, directions_at(-np.cos(np.radians(deg))), 400_000, 1)
    assert abs(mean - expected) < 4.5 * err + 5e-4, (mean, err)


@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
@pytest.mark.parametrize("alpha", [0.3, 0.8])
@pytest.mark.parametrize("cos_theta", [1.0, 0.15, -1.0, -0.5])
def test_02_compensated_lossless_dielectric_conserves_energy_from_both_sides(dist, alpha, cos_theta):
    """R + T = 1 within 4.5 sigma (the sampled estimate's noise; Sidak over 16 cases at
    1 %) plus the tables' error; the single-scattering model falls short where it loses
    more than that."""
    wi = directions_at(cos_theta)
    comp = bl.RoughDielectric(alpha, 1.5, 1.0, distribution=dist, multiscatter=True)
    mean, err = _unscaled_energy(comp, wi, 100_000, 2)
    assert abs(mean - 1.0) < 4.5 * err + TABLE_ERROR, (mean, err)
    single, serr = _unscaled_energy(bl.RoughDielectric(alpha, 1.5, 1.0, distribution=dist), wi,
                                    100_000, 2)
    if 1.0 - single > 10 * (serr + TABLE_ERROR):
        assert mean - single > 5 * np.hypot(err, serr)


@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
@pytest.mark.parametrize("alpha", [0.1, 0.5, 1.0])
def test_03_white_conductor_conserves_energy_and_tables_match_the_single_scattering_albedo(dist, alpha):
    """A compensated F = 1 conductor has albedo 1 (both estimators, 4.5 sigma + table
    error); the tabulated single-scattering albedo agrees with the uncompensated model's
    Monte Carlo albedo within 4.5 sigma + TABLE_ERROR at several angles."""
    comp = bl.RoughConductor(alpha, distribution=dist, multiscatter=True)
    plain = bl.RoughConductor(alpha, distribution=dist)
    core = comp._core(np.array([550.0]))
    for cos_theta in (1.0, 0.6, 0.2, 0.05):
        wi = directions_at(cos_theta)
        s = albedo_sampled(comp, wi, n=100_000, seed=3, wavelengths=[550.0])
        assert abs(s.mean[0] - 1.0) < 4.5 * s.stderr[0] + TABLE_ERROR, (cos_theta, s)
        e = albedo_sampled(plain, wi, n=100_000, seed=4, wavelengths=[550.0])
        table = core.single_scattering_albedo(0, cos_theta)[0]
        assert abs(table - e.mean[0]) < 4.5 * e.stderr[0] + TABLE_ERROR, (cos_theta, table, e)


_slow = pytest.mark.slow  # (the coloured and film cases build tables over many wavelengths)
CHI2_CASES = [
    (lambda: bl.RoughDielectric(0.6, 1.5, 1.0, distribution="beckmann", multiscatter=True), 0.1),
    (lambda: bl.RoughDielectric(0.5, 1.5, 1.0, multiscatter=True), 0.6),
    (lambda: bl.RoughDielectric(0.5, 1.5, 1.0, multiscatter=True), -0.6),
    (lambda: bl.RoughDielectric(0.8, 1.0, 1.33, distribution="beckmann", multiscatter=True), -0.9),
    pytest.param(lambda: bl.RoughConductor(0.5, material="Au", multiscatter=True), 0.7, marks=_slow),
    pytest.param(lambda: bl.RoughConductor(0.8, material="Cu", two_sided=True, multiscatter=True),
                 -0.3, marks=_slow),
    pytest.param(lambda: bl.RoughConductor(0.4, material="Al", film=FILM, multiscatter=True), 0.5,
                 marks=_slow),
    pytest.param(lambda: bl.RoughDielectric(0.3, 1.5, 1.0, film=FILM, multiscatter=True), -0.4,
                 marks=_slow),
    pytest.param(lambda: bl.RoughConductor(0.6, distribution="beckmann", multiscatter=True), 0.1,
                 marks=_slow),
]


@pytest.mark.parametrize("make, cos_theta", CHI2_CASES)
def test_04_chi2_of_the_mixture_sampler(make, cos_theta):
    test = bsdf_chi2(make(), directions_at(cos_theta), significance=SIGNIFICANCE,
                     test_count=len(CHI2_CASES), sample_count=200_000, seed=5,
                     quadrature_order=8)
    assert test.run(), test.message


ALL_CASES = [c.values if hasattr(c, "values") else c for c in CHI2_CASES]  # none slow


@pytest.mark.parametrize("make, cos_theta", ALL_CASES)
def test_05_eval_pdf_consistency(make, cos_theta):
    r = eval_pdf_consistency(make(), directions_at(cos_theta), n=2_000, seed=6)
    assert r.max_pdf_error < 1e-8 and r.max_weight_error < 1e-8, r


def test_06_reciprocity():
    for m in (bl.RoughConductor(0.5, material="Au", multiscatter=True),
              bl.RoughDielectric(0.5, 1.5, 1.0, multiscatter=True),
              bl.RoughDielectric(0.5, 1.5, 1.0, film=FILM, multiscatter=True)):
        wi = random_unit_vectors(2000, seed=7, hemisphere="upper")
        wo = random_unit_vectors(2000, seed=8, hemisphere="upper")
        assert np.max(reciprocity_error(m, wi, wo, wavelengths=[450.0, 550.0, 650.0])) < 1e-9
    # transmission (Veach's generalised reciprocity; see test_rough_interfaces.test_06)
    eta = 1.5
    g = bl.RoughDielectric(0.5, eta, 1.0, multiscatter=True)
    wi = random_unit_vectors(2000, seed=9, hemisphere="upper")
    wo = random_unit_vectors(2000, seed=10, hemisphere="lower")
    f_io = g.eval(wi, wo, wavelengths=[550.0])[:, 0] / np.abs(wo[:, 2])
    f_oi = g.eval(wo, wi, wavelengths=[550.0])[:, 0] / np.abs(wi[:, 2])
    assert np.all(f_io > 0)  # the compensation lobe reaches every pair
    assert np.allclose(f_oi, eta**2 * f_io, rtol=1e-9, atol=0)


def test_07_uniform_and_sampled_albedo_agree_for_a_coloured_conductor():
    m = bl.RoughConductor(0.6, material="Au", multiscatter=True)
    wi = directions_at(0.4)
    u = albedo_uniform(m, wi, n=400_000, seed=11, wavelengths=[450.0, 650.0])
    s = albedo_sampled(m, wi, n=100_000, seed=12, wavelengths=[450.0, 650.0])
    assert np.all(np.abs(u.mean - s.mean) < 4.5 * np.hypot(u.stderr, s.stderr))


def test_08_defaults_and_dicts():
    m = bl.RoughDielectric(0.3, 1.5, 1.0)
    assert m.multiscatter is False and m.distribution == "ggx"
    assert "multiscatter" not in m.to_dict() and "distribution" not in m.to_dict()
    c = bl.RoughConductor(0.3, material="Au", distribution="beckmann", multiscatter=True)
    d = c.to_dict()
    assert d["distribution"] == "beckmann" and d["multiscatter"] is True
    assert bl.from_dict(d) == c
    with pytest.raises(ValueError, match="multiscatter"):
        bl.RoughConductor(0.3, multiscatter="yes")


# -- against the microsurface oracle -------------------------------------------------------
# Kulla-Conty's lobe models the multiply scattered light, it is not exact; and bsdflab's
# single scattering uses the separable G1 G1 (Mitsuba's), the oracle the height-correlated
# G2, which keeps more light at grazing angles. The bounds are the measured differences
# (docs/rough_interfaces.md: Au 550 nm: -0.0025 / -0.0076 at alpha 0.3, 0 / 60 deg;
# -0.025 / -0.040 at alpha 0.8) rounded up, plus 4.5 sigma of both estimates' noise.
KC_CONDUCTOR_ERROR = {0.3: 0.012, 0.8: 0.05}
KC_SPLIT_ERROR = 0.03       # reflected share of a dielectric's energy


@pytest.mark.parametrize("alpha", [0.3, 0.8])
def test_09_compensated_conductor_albedo_against_the_oracle(alpha):
    """Au (550 nm), GGX, at 0 and 60 deg: the compensated albedo against the random walk's
    (all scattering orders), and the compensation closes >= 85 % of the single-scattering
    model's gap to it."""
    au = bl.RoughConductor(alpha, material="Au", multiscatter=True)
    plain = bl.RoughConductor(alpha, material="Au")
    n_rel = au.eta.at([550.0])[0] + 1j * au.k.at([550.0])[0]
    for deg in (0, 60):
        wi = directions_at(np.cos(np.radians(deg)), phi=0.0)
        walks = ms.random_walk(wi, 100_000, alpha, "ggx", conductor_index=n_rel / au.ext_ior,
                               seed=13)
        ref, ref_err = walks.moments(walks.side == 1)
        s = albedo_sampled(au, wi, n=100_000, seed=14, wavelengths=[550.0])
        p = albedo_sampled(plain, wi, n=100_000, seed=14, wavelengths=[550.0])
        noise = 4.5 * np.hypot(ref_err[0], s.stderr[0])
        assert abs(s.mean[0] - ref[0]) < noise + KC_CONDUCTOR_ERROR[alpha], (deg, s.mean, ref)
        assert ref[0] - s.mean[0] < 0.15 * (ref[0] - p.mean[0]) + noise, (deg, s.mean, p.mean, ref)


@pytest.mark.parametrize("cos_theta", [0.8, -0.8, -0.5])
def test_10_dielectric_reflection_share_against_the_oracle(cos_theta):
    """The reflected share of the energy of a compensated GGX alpha 0.5, eta 1.5 interface
    against the random walk's."""
    g = bl.RoughDielectric(0.5, 1.5, 1.0, multiscatter=True)
    wi = directions_at(cos_theta, phi=0.0)
    walks = ms.random_walk(wi, 100_000, 0.5, "ggx", eta=1.5, seed=15)
    side = 1 if cos_theta > 0 else -1
    ref, ref_err = walks.moments(walks.side == side)
    s = g.sample(np.tile(wi, (100_000, 1)), seed=16, wavelengths=[550.0])
    refl = np.where(s.lobe == Lobe.GLOSSY_REFLECTION, s.weight[:, 0], 0.0)
    r, r_err = refl.mean(), refl.std() / np.sqrt(len(refl))
    tol = 4.5 * np.hypot(ref_err[0], r_err) + KC_SPLIT_ERROR
    assert abs(r - ref[0]) < tol, (r, ref)


THREADS_SCRIPT = """
import numpy as np, bsdflab as bl
rng = np.random.default_rng(7)
v = rng.normal(size=(20000, 3)); v /= np.linalg.norm(v, axis=1, keepdims=True)
w = rng.normal(size=(20000, 3)); w /= np.linalg.norm(w, axis=1, keepdims=True)
out = []
for m in (bl.RoughDielectric(0.5, 1.5, 1.0, multiscatter=True, film=[dict(material=2.0, thickness_nm=400.0)]),
          bl.RoughConductor(0.4, material='Au', distribution='beckmann', multiscatter=True)):
    s = m.sample(v, seed=3, wavelengths=[450.0, 550.0, 650.0])
    t = rng.uniform(0, 500, len(v))
    out += [m.eval(v, w, wavelengths=[450.0, 550.0, 650.0], thickness_nm=t),
            m.pdf(v, w, wavelengths=[450.0, 550.0, 650.0]), s.wo, s.weight, s.pdf]
np.save({path!r}, np.concatenate([np.ravel(a) for a in out]))
"""


def test_11_one_thread_equals_many(tmp_path):
    """The compensated cores (their tables, the per-thread buffers of the tint at a query
    thickness) give bit-identical answers on 1 and 2 threads."""
    import os
    import subprocess
    import sys
    results = []
    for threads in ("1", "2"):
        path = tmp_path / f"t{threads}.npy"
        env = dict(os.environ, BSDFLAB_THREADS=threads)
        subprocess.run([sys.executable, "-c", THREADS_SCRIPT.format(path=str(path))], check=True,
                       env=env, timeout=300)
        results.append(path.read_bytes())
    assert results[0] == results[1]


# Measured (docs/rough_interfaces.md): largest per-bin difference 0.003 at alpha 0.3, 0.0085
# (Beckmann) and 0.015 (GGX) at alpha 0.8; bounds rounded up.
LOBE_BIN_ERROR = {0.3: 0.005, 0.8: 0.012}
MU_EDGES = np.linspace(0.0, 1.0, 9)


def _binned_energy(wo, energy):
    """Energy fraction leaving in 8 |cos theta| bins on each side (2, 8), and its standard
    error (multinomial-weighted sample means)."""
    n = len(wo)
    mean, err = np.zeros((2, 8)), np.zeros((2, 8))
    for k, side in enumerate((1, -1)):
        out = wo[:, 2] * side > 0
        idx = np.clip(np.digitize(np.abs(wo[out, 2]), MU_EDGES) - 1, 0, 7)
        s1 = np.bincount(idx, weights=energy[out], minlength=8) / n
        s2 = np.bincount(idx, weights=energy[out] ** 2, minlength=8) / n
        mean[k], err[k] = s1, np.sqrt(np.maximum(s2 - s1 * s1, 0.0) / n)
    return mean, err


@pytest.mark.parametrize("dist, alpha, cos_theta", [
    ("ggx", 0.3, -0.866), ("ggx", 0.3, 0.5), ("beckmann", 0.8, -0.866)])
def test_12_lobe_shape_against_the_oracle(dist, alpha, cos_theta):
    """Where the energy goes, binned in |cos theta_o| on both sides (16 bins): the
    compensated model against the random walk within 4.5 sigma (both estimates' noise)
    plus the measured model error per bin; from inside, the single-scattering model is
    rejected by the same bound (the compensation is what makes the lobes agree)."""
    n = 200_000
    wi = directions_at(cos_theta, phi=0.0)
    walks = ms.random_walk(wi, n, alpha, dist, eta=1.5, seed=21)
    ref, ref_err = _binned_energy(walks.wo, walks.energy[:, 0])
    tol = LOBE_BIN_ERROR[alpha]
    for multiscatter in (True, False):
        g = bl.RoughDielectric(alpha, 1.5, 1.0, distribution=dist, multiscatter=multiscatter)
        s = g.sample(np.tile(wi, (n, 1)), seed=22, wavelengths=[550.0])
        e = np.where(s.lobe == Lobe.GLOSSY_TRANSMISSION, s.weight[:, 0] * s.eta**2, s.weight[:, 0])
        got, err = _binned_energy(s.wo, e)
        excess = np.abs(got - ref) - 4.5 * np.hypot(err, ref_err)
        if multiscatter:
            assert np.all(excess < tol), (np.round(got, 4), np.round(ref, 4))
        elif cos_theta < 0:
            assert np.any(excess > tol)
