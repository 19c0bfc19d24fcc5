"""Compare two Monte Carlo images pixel by pixel: do they estimate the same image?

``image_z_test(mean_a, var_a, mean_b, var_b)`` takes each image's per-pixel means and the
variance of those means (what ``bsdflab.render.render`` and
``bsdflab.reference.mitsuba_render.render_mitsuba`` return) and tests every pixel and
channel with the two-sample statistic

    z = (a - b) / sqrt(var_a + var_b + (rtol * max(|a|, |b|))^2)

which is standard normal when both images are unbiased estimates of the same image and the
pixel means are Gaussian (central limit theorem over spp samples). The small ``rtol`` term
stands for float32 rounding in a renderer's accumulation; it keeps near-deterministic pixels
(an emitter seen directly) from producing huge z out of rounding alone. Pixel-channels
where both variances are exactly 0 are checked for equality to that same tolerance instead.

Significance: the two-sided p-value of each z is compared with the Sidak-corrected level
1 - (1 - alpha)^(1/m) over the m tested pixel-channels, so a pair of correct images fails
with probability alpha (at most alpha: channels of one pixel are positively correlated,
for which Sidak is conservative). ``block`` > 1 averages block x block pixels first (means
average, variances average / block^2): fewer, more Gaussian statistics, and more power
against small biases that cover an area; rows and columns beyond the last whole block are
dropped.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.special import erfc

from bsdflab.util import args as check

DEFAULT_RTOL = 1e-4
DEFAULT_ATOL = 1e-12


@dataclass(frozen=True)
class ImageTestResult:
    """The outcome of ``image_z_test``; arrays are per (block) pixel and channel."""

    passed: bool
    alpha: float
    block: int
    n_tested: int           # pixel-channels tested by z (Sidak count)
    n_exact: int            # pixel-channels with both variances 0, checked for equality
    level: float            # per-test significance after the Sidak correction
    n_rejected: int         # z rejections plus failed equality checks plus non-finite values
    min_p: float            # smallest p-value (0 for a failed equality check or non-finite value)
    worst: tuple[int, int, int]  # (row, column, channel) of min_p in the original image (block's top left)
    worst_z: float
    z: np.ndarray = field(repr=False)
    p: np.ndarray = field(repr=False)
    mean_a: np.ndarray = field(repr=False)
    mean_b: np.ndarray = field(repr=False)

    def summary(self) -> str:
        r, c, ch = self.worst
        verdict = "PASS" if self.passed else "FAIL"
        return (f"{verdict}: {self.n_rejected} of {self.n_tested + self.n_exact} pixel-channels rejected "
                f"(block {self.block}, alpha {self.alpha:g}, per-test level {self.level:.2e}); "
                f"min p {self.min_p:.3e} at row {r}, column {c}, channel {ch} (z = {self.worst_z:+.2f}; "
                f"a = {self.mean_a[r // self.block, c // self.block, ch]:.6g}, "
                f"b = {self.mean_b[r // self.block, c // self.block, ch]:.6g})")

    def plot(self, path, title: str = "", labels: tuple[str, str] = ("image a", "image b")) -> Path:
        """A PNG with both images (same exposure, gamma 2.2) and the map of z (the channel
        with the largest |z| per pixel); rejected pixels are circled."""
        from bsdflab.testing._image_figure import z_test_figure

        return z_test_figure(self, path, title, labels)


def _as_image(name: str, value) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or min(a.shape) < 1:
        raise ValueError(f"{name} must be an (H, W) or (H, W, C) array, got shape {np.shape(value)}")
    return a


def block_average(mean: np.ndarray, var: np.ndarray, block: int) -> tuple[np.ndarray, np.ndarray]:
    """Block x block averages of per-pixel means and the variances of those averages
    (independent pixels: mean variance / block^2); incomplete edge blocks are dropped."""
    h, w = mean.shape[0] // block * block, mean.shape[1] // block * block
    if h == 0 or w == 0:
        raise ValueError(f"block {block} is larger than the image ({mean.shape[0]} x {mean.shape[1]})")

    def avg(x):
        x = x[:h, :w]
        return x.reshape(h // block, block, w // block, block, -1).mean(axis=(1, 3))

    return avg(mean), avg(var) / block**2


def image_z_test(mean_a, var_a, mean_b, var_b, alpha: float = 0.01, block: int = 1,
                 rtol: float = DEFAULT_RTOL, atol: float = DEFAULT_ATOL) -> ImageTestResult:
    """Test whether two Monte Carlo images have the same expectation (see module docstring).

    mean_a, mean_b : (H, W) or (H, W, C) pixel means.
    var_a, var_b : the variances of those means (not of single samples), same shape, >= 0.
    alpha : false-alarm probability for the whole image, in (0, 1).
    block : side of the square pixel blocks averaged before testing (1 = per pixel).
    rtol, atol : float tolerance (see module docstring).
    """
    ma, va, mb, vb = (_as_image(n, x) for n, x in
                      (("mean_a", mean_a), ("var_a", var_a), ("mean_b", mean_b), ("var_b", var_b)))
    if not ma.shape == va.shape == mb.shape == vb.shape:
        raise ValueError(f"shapes differ: mean_a {ma.shape}, var_a {va.shape}, mean_b {mb.shape}, var_b {vb.shape}")
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha!r}")
    block = check.integer("block", block, 1)
    if not (rtol >= 0 and atol >= 0):
        raise ValueError(f"rtol and atol must be >= 0, got {rtol!r}, {atol!r}")
    if np.any(va < 0) or np.any(vb < 0):
        raise ValueError("variances must be >= 0")

    block = int(block)
    ma, va = block_average(ma, va, block)
    mb, vb = block_average(mb, vb, block)

    finite = np.isfinite(ma) & np.isfinite(mb) & np.isfinite(va) & np.isfinite(vb)
    exact = finite & (va == 0) & (vb == 0)
    tested = finite & ~exact
    diff = np.where(finite, ma - mb, 0.0)
    tol = rtol * np.maximum(np.abs(np.where(finite, ma, 0)), np.abs(np.where(finite, mb, 0))) + atol
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(tested, diff / np.sqrt(np.where(finite, va + vb, 0) + tol**2), 0.0)
    p = np.where(tested, erfc(np.abs(z) / np.sqrt(2.0)), 1.0)
    p = np.where(exact & (np.abs(diff) > tol), 0.0, p)
    p = np.where(finite, p, 0.0)
    z = np.where(exact & (np.abs(diff) > tol), np.copysign(np.inf, diff), z)
    z = np.where(finite, z, np.nan)

    n_tested = int(tested.sum())
    level = -np.expm1(np.log1p(-alpha) / max(n_tested, 1))  # 1 - (1 - alpha)^(1/m), stably
    rejected = (tested & (p < level)) | (p == 0.0)
    worst_index = np.unravel_index(int(np.argmin(p)), p.shape)
    r, c, ch = (int(i) for i in worst_index)
    return ImageTestResult(
        passed=not bool(rejected.any()), alpha=float(alpha), block=block, n_tested=n_tested,
        n_exact=int(exact.sum()), level=float(level), n_rejected=int(rejected.sum()),
        min_p=float(p[worst_index]), worst=(r * block, c * block, ch), worst_z=float(z[worst_index]),
        z=z, p=p, mean_a=ma, mean_b=mb)


def relative_mse(image, reference, epsilon: float = 1e-2) -> float:
    """Mean over pixels and channels of (image - reference)^2 / (reference^2 + epsilon): the
    usual error metric of rendering benchmarks (epsilon keeps dark pixels from dominating)."""
    a, b = np.asarray(image, dtype=np.float64), np.asarray(reference, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"shapes differ: {a.shape} vs {b.shape}")
    if not epsilon > 0:
        raise ValueError(f"epsilon must be > 0, got {epsilon!r}")
    return float(np.mean((a - b) ** 2 / (b**2 + epsilon)))
