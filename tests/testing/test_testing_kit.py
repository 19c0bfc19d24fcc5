"""The BSDF testing kit (bsdflab.testing): chi-square sampler tests, discrete-choice tests,
white-furnace integrals and consistency checks.

Statistical tests here use fixed seeds, so every outcome is deterministic. Unless a
test says otherwise, a chi-square or discrete-choice test runs at significance 0.01:
a correct sampler would be rejected with probability 1%, and the samplers that must be
rejected are rejected with p-values far below 0.01 at the sample counts used.
"""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.testing import (
    ChiSquareTest,
    albedo_sampled,
    albedo_uniform,
    bsdf_chi2,
    discrete_choice_chi2,
    eval_pdf_consistency,
    pearson_chi2,
    pool_low_expected,
    random_unit_vectors,
    reciprocity_error,
    sidak_significance,
    spherical_directions,
)

ALPHA = 0.01          # significance of every statistical test in this file
CHI2_SAMPLES = 200_000
# A furnace estimate must match its target within 4 standard errors (two-sided
# probability of a false alarm 6e-5). Lambertian sample weights are constant, so their
# standard error is ~0; ROUNDING covers float rounding of the RGB projection.
SIGMAS = 4.0
ROUNDING = 1e-9


# -- samplers under test (numpy, no bsdflab) ---------------------------------------------
def cosine_hemisphere(n, seed):
    """Cosine-weighted directions on the upper hemisphere (Malley's method)."""
    u = np.random.default_rng(seed).random((n, 2))
    r, phi = np.sqrt(u[:, 0]), 2.0 * np.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - u[:, 0])], axis=1)


def uniform_hemisphere(n, seed):
    u = np.random.default_rng(seed).random((n, 2))
    z, phi = u[:, 0], 2.0 * np.pi * u[:, 1]
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def cosine_pdf(wo):
    return np.maximum(wo[:, 2], 0.0) / np.pi


def tilted_cosine_pdf(wo):
    """cos/pi times (1 + 0.1 cos), renormalised: the integral of cos^2/pi is 2/3."""
    c = np.maximum(wo[:, 2], 0.0)
    return c * (1.0 + 0.1 * c) / np.pi / (1.0 + 0.1 * 2.0 / 3.0)


# -- statistical pieces on tiny inputs with known answers --------------------------------
def test_sidak_correction_known_values():
    assert sidak_significance(0.01, 1) == pytest.approx(0.01)
    assert sidak_significance(0.05, 2) == pytest.approx(1.0 - np.sqrt(0.95))
    level = sidak_significance(0.01, 10)
    assert level == pytest.approx(0.00100453, rel=1e-5)
    # Ten independent tests at that level together fail a correct sampler 1% of the time.
    assert 1.0 - (1.0 - level) ** 10 == pytest.approx(0.01)
    for bad in [(0.0, 1), (1.0, 1), (0.01, 0)]:
        with pytest.raises(ValueError):
            sidak_significance(*bad)


def test_pooling_merges_low_cells_and_tops_them_up():
    # Cells expecting 2 and 1 are below 5; together (3) still too few, so the next
    # smallest cell (12) joins the pool.
    pooled = pool_low_expected([3, 1, 10, 20], [2, 1, 12, 19], min_expected=5)
    np.testing.assert_array_equal(pooled.expected, [19, 15])
    np.testing.assert_array_equal(pooled.observed, [20, 14])
    assert pooled.pooled_in == 3


def test_pooling_keeps_enough_cells_and_drops_empty_ones():
    pooled = pool_low_expected([1, 2, 3, 60, 0], [2, 3, 4, 50, 0], min_expected=5)
    np.testing.assert_array_equal(pooled.expected, [50, 9])   # 2 + 3 + 4 = 9 >= 5
    np.testing.assert_array_equal(pooled.observed, [60, 6])
    assert pooled.pooled_in == 3
    untouched = pool_low_expected([7, 9], [8, 8])
    assert untouched.pooled_in == 0 and len(untouched.expected) == 2


def test_pearson_chi2_known_answer():
    r = pearson_chi2([10, 20, 30], [20, 20, 20])
    assert r.statistic == pytest.approx(10.0)
    assert r.dof == 2
    assert r.p_value == pytest.approx(np.exp(-5.0))   # chi2 with 2 dof: sf(x) = exp(-x/2)
    # Pooling lowers the degrees of freedom: 2 cells of 4 merge, leaving 3 cells.
    r = pearson_chi2([2, 3, 50, 45], [2.5, 2.5, 50, 45])
    assert (r.cells, r.dof, r.pooled_in) == (3, 2, 2)
    assert r.statistic == pytest.approx(0.0)


# -- the direction chi-square test -------------------------------------------------------
@pytest.mark.parametrize("cos_theta, seed", [(1.0, 1), (0.05, 2)], ids=["normal", "grazing"])
def test_chi2_accepts_lambertian(cos_theta, seed):
    wi = spherical_directions(np.arccos(cos_theta), 0.3)
    test = bsdf_chi2(bl.Diffuse(0.5), wi, sample_count=CHI2_SAMPLES, seed=seed,
                     significance=ALPHA, test_count=2)   # family of 2, Sidak-corrected
    assert test.run(), test.message
    assert test.significance_per_test == pytest.approx(sidak_significance(ALPHA, 2))
    assert test.pdf_integral == pytest.approx(1.0, abs=1e-6)
    assert test.histogram.sum() == CHI2_SAMPLES
    # No sample below the horizon, and none expected there.
    lower = test.res[0] // 2
    assert test.histogram[:lower].sum() == 0 and test.expected[:lower].sum() == 0


def test_chi2_accepts_two_sided_lambertian_from_below():
    test = bsdf_chi2(bl.Diffuse(0.5, two_sided=True), spherical_directions(2.5, 1.0),
                     sample_count=CHI2_SAMPLES, seed=3, significance=ALPHA)
    assert test.run(), test.message
    assert test.histogram[test.res[0] // 2 + 1:].sum() == 0   # all reflected below


def test_chi2_rejects_uniform_sampler_claiming_cosine_pdf():
    test = ChiSquareTest(uniform_hemisphere, cosine_pdf, sample_count=CHI2_SAMPLES, seed=4,
                         significance=ALPHA)
    assert not test.run()
    assert test.p_value < 1e-12
    assert "REJECTED" in test.message


def test_chi2_rejects_pdf_off_by_a_theta_dependent_factor():
    # The claimed pdf differs from the true cos/pi by at most ~6%, smoothly in theta.
    # 200k samples catch this most of the time; 1M samples (0.2 s) reject it with
    # p-values far below 1e-6 for every seed tried.
    test = ChiSquareTest(cosine_hemisphere, tilted_cosine_pdf, sample_count=1_000_000,
                         seed=5, significance=ALPHA)
    assert not test.run(), test.message
    assert test.p_value < 1e-6


def test_chi2_accepts_own_cosine_sampler_at_fine_resolution():
    test = ChiSquareTest(cosine_hemisphere, cosine_pdf, res=(51, 64),
                         sample_count=CHI2_SAMPLES, seed=6, significance=ALPHA)
    assert test.run(), test.message
    assert test.histogram.shape == (51, 64)


def test_chi2_fails_when_samples_land_where_pdf_is_zero():
    def leaky(n, seed):
        wo = cosine_hemisphere(n, seed)
        wo[::1000, 2] *= -1.0    # 0.1% mirrored below the surface
        return wo

    test = ChiSquareTest(leaky, cosine_pdf, sample_count=CHI2_SAMPLES, seed=7)
    assert not test.run()
    assert test.p_value == 0.0
    assert "expected frequency 0" in test.message


@pytest.mark.parametrize("failed_row", [np.nan, 0.0], ids=["nan", "zeros"])
def test_chi2_counts_failed_samples_against_the_pdf_integral(failed_row):
    def sometimes_fails(n, seed):
        wo = cosine_hemisphere(n, seed)
        wo[np.random.default_rng(seed + 1).random(n) < 0.2] = failed_row
        return wo

    honest = ChiSquareTest(sometimes_fails, lambda wo: 0.8 * cosine_pdf(wo),
                           sample_count=CHI2_SAMPLES, seed=8, significance=ALPHA)
    assert honest.run(), honest.message
    assert honest.expected_dropped == pytest.approx(0.2 * CHI2_SAMPLES, rel=1e-6)
    assert abs(honest.dropped - 0.2 * CHI2_SAMPLES) < 1000

    claims_no_failures = ChiSquareTest(sometimes_fails, cosine_pdf,
                                       sample_count=CHI2_SAMPLES, seed=8)
    assert not claims_no_failures.run()
    assert "produced no direction" in claims_no_failures.message


def test_chi2_input_validation():
    with pytest.raises(ValueError, match="odd"):
        ChiSquareTest(cosine_hemisphere, cosine_pdf, res=30)
    with pytest.raises(ValueError, match="res"):
        ChiSquareTest(cosine_hemisphere, cosine_pdf, res=(31, 0))
    with pytest.raises(ValueError, match="significance"):
        ChiSquareTest(cosine_hemisphere, cosine_pdf, significance=1.5)
    with pytest.raises(ValueError, match="sample_count"):
        ChiSquareTest(cosine_hemisphere, cosine_pdf, sample_count=0)
    with pytest.raises(ValueError, match="callable"):
        ChiSquareTest(None, cosine_pdf)
    with pytest.raises(ValueError, match=r"shape \(100, 3\)"):
        ChiSquareTest(lambda n, seed: np.zeros((n, 2)), cosine_pdf, sample_count=100).run()
    with pytest.raises(ValueError, match="one value per direction"):
        ChiSquareTest(cosine_hemisphere, lambda wo: np.ones(3), sample_count=100).run()


def test_bsdf_chi2_refuses_all_delta_bsdfs():
    with pytest.raises(ValueError, match="discrete_choice_chi2"):
        bsdf_chi2(bl.Dielectric(), [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="single direction"):
        bsdf_chi2(bl.Diffuse(), [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])


def test_chi2_plot_writes_png(tmp_path):
    test = ChiSquareTest(cosine_hemisphere, cosine_pdf, sample_count=20_000, seed=9)
    test.run()
    path = test.plot(tmp_path / "chi2.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# -- discrete choices --------------------------------------------------------------------
def bernoulli_labels(p, n, seed):
    return np.where(np.random.default_rng(seed).random(n) < p, "reflect", "transmit")


def test_discrete_choice_accepts_correct_bernoulli():
    result = discrete_choice_chi2(bernoulli_labels(0.3, 10_000, seed=10),
                                  {"reflect": 0.3, "transmit": 0.7}, significance=ALPHA)
    assert result.passed, result.message
    assert result.method == "exact binomial"


def test_discrete_choice_rejects_wrong_bernoulli():
    # 0.35 vs 0.3 is 11 standard deviations off with 10k trials.
    result = discrete_choice_chi2(bernoulli_labels(0.35, 10_000, seed=11),
                                  {"reflect": 0.3, "transmit": 0.7}, significance=ALPHA)
    assert not result.passed
    assert result.p_value < 1e-12


def test_discrete_choice_with_three_outcomes_and_impossible_ones():
    labels = np.random.default_rng(12).choice(3, size=20_000, p=[0.2, 0.3, 0.5])
    ok = discrete_choice_chi2(labels, {0: 0.2, 1: 0.3, 2: 0.5}, significance=ALPHA)
    assert ok.passed and ok.method == "chi-square" and ok.dof == 2, ok.message
    impossible = discrete_choice_chi2(labels, {0: 0.2, 1: 0.8})
    assert not impossible.passed and impossible.p_value == 0.0
    assert "expected probability 0" in impossible.message


def test_discrete_choice_of_dielectric_lobes_follows_fresnel():
    glass = bl.Dielectric(int_ior=1.5, ext_ior=1.0)
    wi = spherical_directions(np.radians(60.0), 0.0)
    cos_i = np.cos(np.radians(60.0))
    reflectance = float(bl.optics.fresnel_reflectance(cos_i, 1.0, 1.5).unpolarised)
    lobes = glass.sample(np.tile(wi, (100_000, 1)), seed=13).lobe
    result = discrete_choice_chi2(lobes, {bl.Lobe.DELTA_REFLECTION: reflectance,
                                          bl.Lobe.DELTA_TRANSMISSION: 1.0 - reflectance},
                                  significance=ALPHA)
    assert result.passed, result.message


def test_discrete_choice_input_validation():
    with pytest.raises(ValueError, match="sum to 1"):
        discrete_choice_chi2([1, 0], {1: 0.3, 0: 0.6})
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        discrete_choice_chi2([1, 0], {1: 1.5, 0: -0.5})
    with pytest.raises(ValueError, match="empty"):
        discrete_choice_chi2([], {1: 1.0})


# -- white furnace -----------------------------------------------------------------------
WI_FURNACE = spherical_directions(np.radians(40.0), 0.7)


@pytest.mark.parametrize("albedo", [1.0, 0.3])
def test_furnace_lambertian_albedo(albedo):
    bsdf = bl.Diffuse(albedo)
    uniform = albedo_uniform(bsdf, WI_FURNACE, n=200_000, seed=14)
    sampled = albedo_sampled(bsdf, WI_FURNACE, n=200_000, seed=15)
    for estimate in (uniform, sampled):
        assert estimate.mean.shape == (3,) and estimate.n == 200_000
        error = np.abs(estimate.mean - albedo)
        assert np.all(error <= SIGMAS * estimate.stderr + ROUNDING), estimate
    # The two estimators are independent; their difference has the combined error.
    combined = np.hypot(uniform.stderr, sampled.stderr)
    assert np.all(np.abs(uniform.mean - sampled.mean) <= SIGMAS * combined + ROUNDING)


def test_furnace_per_wavelength_and_below_the_surface():
    wavelengths = [450.0, 550.0, 650.0, 700.0]
    estimate = albedo_uniform(bl.Diffuse(0.5), WI_FURNACE, n=20_000, wavelengths=wavelengths)
    assert estimate.mean.shape == estimate.stderr.shape == (4,)
    # A one-sided diffuse surface lit from below scatters nothing; failed samples count 0.
    below = albedo_sampled(bl.Diffuse(0.5), [0.0, 0.0, -1.0], n=1000)
    np.testing.assert_array_equal(below.mean, 0.0)
    with pytest.raises(ValueError, match="n must be an integer >= 1"):
        albedo_uniform(bl.Diffuse(0.5), WI_FURNACE, n=0)


# -- deterministic checks ----------------------------------------------------------------
def test_reciprocity_of_lambertian():
    wi = random_unit_vectors(2000, seed=16)
    wo = random_unit_vectors(2000, seed=17)
    for bsdf in (bl.Diffuse(0.5), bl.Diffuse([0.2, 0.5, 0.9], two_sided=True)):
        error = reciprocity_error(bsdf, wi, wo)
        assert error.shape == (2000, 3)
        assert error.max() < 1e-12
    # Directions on the horizon (cos = 0) compare as 0 rather than 0/0.
    assert reciprocity_error(bl.Diffuse(0.5), [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]).max() == 0.0


def test_eval_pdf_consistency_of_lambertian_and_refusal_for_delta():
    report = eval_pdf_consistency(bl.Diffuse(0.7), WI_FURNACE, n=50_000, seed=18)
    assert report.checked == 50_000 and report.skipped == 0
    assert report.max_weight_error < 1e-12 and report.max_pdf_error < 1e-12
    with pytest.raises(ValueError, match="non-delta"):
        eval_pdf_consistency(bl.Conductor(material="Au"), WI_FURNACE, n=100)


def test_direction_utilities():
    np.testing.assert_allclose(spherical_directions(np.pi / 2, np.pi / 2), [0.0, 1.0, 0.0],
                               atol=1e-15, rtol=0)
    grid = spherical_directions(np.linspace(0, np.pi, 5)[:, None], np.linspace(0, 1, 3))
    assert grid.shape == (5, 3, 3)
    for hemisphere, sign in ((None, 0), ("upper", 1), ("lower", -1)):
        v = random_unit_vectors(5000, seed=19, hemisphere=hemisphere)
        np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-12, rtol=0)
        if sign:
            assert np.all(sign * v[:, 2] >= 0)
        else:
            assert abs(v[:, 2].mean()) < 0.05   # uniform on the sphere: E[z] = 0
    with pytest.raises(ValueError, match="hemisphere"):
        random_unit_vectors(10, hemisphere="up")
    with pytest.raises(ValueError, match="theta"):
        spherical_directions(4.0, 0.0)
