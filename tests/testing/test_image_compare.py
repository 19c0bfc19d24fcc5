"""The image z-test on synthetic Gaussian images with known statistics.

Rates over many seeds are checked with an exact two-sided binomial test at significance
1e-3 (so each such test itself fails a correct implementation 1 time in 1000); the seeds are
fixed, so the outcomes are repeatable.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from bsdflab.testing import image_z_test, relative_mse, sidak_z_limit
from bsdflab.testing.image_compare import block_average

RATE_SIGNIFICANCE = 1e-3
SHAPE = (24, 32, 3)  # 2304 pixel-channels


def _truth(rng, rel_sigma=0.01):
    mu = rng.uniform(0.2, 2.0, SHAPE)
    var = (rel_sigma * mu * rng.uniform(0.5, 2.0, SHAPE)) ** 2  # variance of the pixel mean
    return mu, var


def _draw(rng, mu, var):
    return mu + rng.normal(size=mu.shape) * np.sqrt(var)


def _binomial_ok(k: int, n: int, p: float) -> bool:
    return stats.binomtest(k, n, p).pvalue > RATE_SIGNIFICANCE


def test_false_alarm_rate_is_alpha_with_known_variances():
    alpha, trials = 0.05, 1000
    rng = np.random.default_rng(1)
    mu, var = _truth(rng)
    failures = sum(not image_z_test(_draw(rng, mu, var), var, _draw(rng, mu, var), var, alpha=alpha).passed
                   for _ in range(trials))
    assert _binomial_ok(failures, trials, alpha), (
        f"{failures} false alarms in {trials} (expected ~{alpha * trials:.0f})")


def test_false_alarm_rate_with_variances_estimated_from_samples():
    """Renderers estimate each pixel's variance from its spp samples: the sample variance is
    sigma^2 chi^2_(n-1) / (n-1), independent of the Gaussian mean; at 1024 spp the rate stays
    at alpha (the extra t-tail is far below what 1000 trials resolve)."""
    alpha, trials, n = 0.05, 1000, 1024
    rng = np.random.default_rng(2)
    mu, var = _truth(rng)

    def estimated():
        return _draw(rng, mu, var), var * rng.chisquare(n - 1, SHAPE) / (n - 1)

    failures = sum(not image_z_test(*estimated(), *estimated(), alpha=alpha).passed for _ in range(trials))
    assert _binomial_ok(failures, trials, alpha), (
        f"{failures} false alarms in {trials} (expected ~{alpha * trials:.0f})")


def test_single_pixel_five_sigma_shift_is_detected():
    rng = np.random.default_rng(3)
    mu, var = _truth(rng)
    a, b = _draw(rng, mu, var), _draw(rng, mu, var)
    a[7, 11, 1], b[7, 11, 1] = mu[7, 11, 1] + 5 * np.sqrt(2 * var[7, 11, 1]), mu[7, 11, 1]
    r = image_z_test(a, var, b, var, alpha=0.01)
    assert not r.passed and r.n_rejected == 1
    assert r.worst == (7, 11, 1) and r.worst_z == pytest.approx(5.0, rel=1e-3)  # rtol floor


def test_power_against_a_five_sigma_shift_matches_theory():
    """With noise, z at the shifted pixel is N(5, 1): detection probability is
    P(|N(5, 1)| > z_crit) (plus the small chance of a false alarm elsewhere)."""
    alpha, trials = 0.01, 600
    rng = np.random.default_rng(4)
    mu, var = _truth(rng)
    shift = mu.copy()
    shift[5, 5, 0] += 5 * np.sqrt(2 * var[5, 5, 0])
    detected = sum(not image_z_test(_draw(rng, shift, var), var, _draw(rng, mu, var), var, alpha=alpha).passed
                   for _ in range(trials))
    m = np.prod(SHAPE)
    z_crit = sidak_z_limit(alpha, m)
    power = stats.norm.sf(z_crit - 5) + stats.norm.cdf(-z_crit - 5)
    expected = 1 - (1 - power) * (1 - alpha) ** ((m - 1) / m)
    assert _binomial_ok(detected, trials, expected), f"detected {detected}/{trials}, expected {expected:.3f}"


def test_two_percent_bias_everywhere_is_detected():
    rng = np.random.default_rng(5)
    mu, var = _truth(rng, rel_sigma=0.001)  # z >= 7 everywhere
    r = image_z_test(_draw(rng, 1.02 * mu, var), var, _draw(rng, mu, var), var, alpha=0.01)
    assert not r.passed and r.n_rejected > 0.9 * r.n_tested


def test_blocks_detect_a_bias_too_small_for_single_pixels():
    """2 % bias under 1.5 % per-pixel noise: z ~ 0.9 per pixel, ~7.5 per 8x8 block."""
    rng = np.random.default_rng(6)
    mu = np.full(SHAPE, 1.0)
    var = np.full(SHAPE, 0.015**2)
    a, b = _draw(rng, 1.02 * mu, var), _draw(rng, mu, var)
    assert not image_z_test(a, var, b, var, alpha=0.01, block=8).passed


def test_block_average_of_means_and_variances():
    mean = np.arange(5 * 7 * 3, dtype=float).reshape(5, 7, 3)
    var = np.ones_like(mean)
    m, v = block_average(mean, var, 2)
    assert m.shape == v.shape == (2, 3, 3)  # the last row and column are dropped
    assert m[1, 2, 0] == pytest.approx(mean[2:4, 4:6, 0].mean())
    assert np.allclose(v, 1 / 4, rtol=1e-14, atol=0)
    with pytest.raises(ValueError, match="larger than the image"):
        block_average(mean, var, 8)


def test_sidak_level():
    rng = np.random.default_rng(7)
    mu, var = _truth(rng)
    r = image_z_test(mu, var, mu, var, alpha=0.01)
    assert r.passed and r.n_tested == np.prod(SHAPE) and r.min_p == 1.0
    assert r.level == pytest.approx(1 - 0.99 ** (1 / np.prod(SHAPE)), rel=1e-12)


def test_zero_variance_pixels_must_match_to_float_tolerance():
    mu = np.full((4, 4, 3), 2.0)
    zero = np.zeros_like(mu)
    r = image_z_test(mu, zero, mu * (1 + 1e-6), zero)
    assert r.passed and r.n_exact == mu.size and r.n_tested == 0
    off = mu.copy()
    off[1, 2, 0] *= 1.001
    r = image_z_test(off, zero, mu, zero)
    assert not r.passed and r.n_rejected == 1 and r.min_p == 0.0 and r.worst == (1, 2, 0)
    # black vs black passes; black vs anything else fails
    assert image_z_test(zero, zero, zero, zero).passed
    assert not image_z_test(zero, zero, zero + 1e-6, zero).passed


def test_one_zero_variance_side_uses_the_other_variance():
    mu = np.full((4, 4, 3), 1.0)
    var = np.full_like(mu, 0.01**2)
    ok = mu + 0.02  # z = 2: accepted for 48 tests at alpha 0.01
    bad = mu + 0.06  # z = 6: rejected
    assert image_z_test(ok, var, mu, np.zeros_like(mu)).passed
    assert not image_z_test(bad, var, mu, np.zeros_like(mu)).passed


def test_non_finite_values_fail():
    mu = np.full((4, 4, 3), 1.0)
    var = np.full_like(mu, 0.01)
    nan = mu.copy()
    nan[0, 0, 2] = np.nan
    r = image_z_test(nan, var, mu, var)
    assert not r.passed and r.worst == (0, 0, 2)


@pytest.mark.parametrize("bad", [dict(alpha=0.0), dict(alpha=1.0), dict(block=0), dict(block=1.5), dict(rtol=-1.0)])
def test_bad_arguments(bad):
    mu = np.ones((4, 4, 3))
    with pytest.raises(ValueError):
        image_z_test(mu, mu, mu, mu, **bad)


def test_bad_shapes_and_negative_variance():
    mu = np.ones((4, 4, 3))
    with pytest.raises(ValueError, match="shapes differ"):
        image_z_test(mu, mu, mu[:3], mu[:3])
    with pytest.raises(ValueError, match=">= 0"):
        image_z_test(mu, -mu, mu, mu)


def test_figure_is_written(tmp_path):
    rng = np.random.default_rng(8)
    mu, var = _truth(rng)
    a = _draw(rng, mu, var)
    a[3, 4] += 0.5
    r = image_z_test(a, var, _draw(rng, mu, var), var)
    out = r.plot(tmp_path / "z.png", labels=("shifted", "reference"))
    assert out.exists() and out.stat().st_size > 1000
    assert "FAIL" in r.summary()


def test_relative_mse():
    ref = np.full((2, 2, 3), 1.0)
    assert relative_mse(ref, ref) == 0.0
    assert relative_mse(ref * 1.1, ref, epsilon=1e-2) == pytest.approx(0.01 / 1.01)
