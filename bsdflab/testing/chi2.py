"""Chi-square goodness-of-fit test of a direction sampler against its claimed pdf.

The method follows Mitsuba 3's ``chi2.py``: draw many samples, histogram them over a
grid on the sphere, integrate the claimed pdf numerically over every cell to get the
expected counts, pool cells with too few expected counts, and compute Pearson's
chi-square statistic and its p-value. A sampler whose samples do not follow its pdf
(wrong sampling, wrong pdf, wrong normalisation) is rejected once enough samples are
drawn.

The grid covers the whole sphere, so transmission is tested too: rows are cos(theta)
in [-1, 1] (z < 0 is below the surface), columns phi in [-pi, pi]. Because the map
(cos theta, phi) -> direction preserves area up to a constant, every cell of the grid
has the same solid angle 4 pi / cells. Samples that produce no direction (a failed
sample, or a delta lobe that the pdf cannot describe) form one more category whose
expected count is ``sample_count * (1 - integral of pdf)``.

Delta lobes (pdf zero everywhere) are outside this test; check their discrete
choices with ``discrete_choice_chi2``.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bsdflab.lobes import Lobe
from bsdflab.testing.directions import directions_from_cos_phi, positive_int, single_direction
from bsdflab.testing.discrete import discrete_choice_chi2
from bsdflab.testing.stats import check_significance, pearson_chi2, sidak_significance
from bsdflab.util import args as check

__all__ = ["ChiSquareTest", "bsdf_chi2", "discrete_choice_chi2"]

SampleFn = Callable[[int, int], np.ndarray]
PdfFn = Callable[[np.ndarray], np.ndarray]

# A pdf may integrate to slightly more than 1 through quadrature error on sharp
# features; beyond this it is a bug worth naming outright.
PDF_INTEGRAL_TOLERANCE = 1e-2
# Gauss-Legendre integrals of smooth pdfs are exact to about this level.
QUADRATURE_ROUNDING = 1e-9


class ChiSquareTest:
    """Pearson's chi-square test that ``sample_fn`` draws directions with density ``pdf_fn``.

    Parameters
    ----------
    sample_fn : callable ``(n, seed) -> (n, 3) array``
        Draws ``n`` directions. Rows containing NaN, or all zero, mean "no direction"
        (a failed sample); they are dropped from the histogram but counted.
        Every other row must be a unit vector.
    pdf_fn : callable ``(wo (M, 3)) -> (M,) array``
        Solid-angle density claimed for ``sample_fn``. It may integrate to less than 1
        when some samples fail; the shortfall is the expected failure rate.
    res : int or (int, int)
        Grid resolution ``(n_theta, n_phi)``; an int ``r`` means ``(r, 2 r)``. ``n_theta``
        must be odd so that the horizon z = 0 runs through the middle of a row of cells
        rather than along a cell boundary, where rounding would decide the cell.
        Default 31, i.e. a 31 x 62 grid.
    sample_count : int
        Number of samples. More samples detect smaller errors. Default 1,000,000.
    min_expected : float
        Cells expecting fewer samples than this are pooled (chi-square approximation).
        Default 5.
    significance : float in (0, 1)
        Family-wise probability of wrongly rejecting a correct sampler. Default 0.01.
    test_count : int
        Number of tests in the family this test belongs to; the per-test level is the
        Sidak-corrected ``1 - (1 - significance) ** (1 / test_count)``.
    seed : int
        Passed to ``sample_fn``; fix it for repeatable results.
    quadrature_order : int
        Gauss-Legendre nodes per axis used to integrate the pdf over each cell (the
        cos(theta) axis of the horizon row is split at z = 0 and integrated on each
        side, since pdfs are typically discontinuous there). Default 5.

    Attributes
    ----------
    histogram : (n_theta, n_phi) ndarray or None
        Observed counts; row 0 is cos(theta) near -1, column 0 is phi near -pi.
    expected : (n_theta, n_phi) ndarray or None
        ``sample_count`` times the pdf integrated over each cell.
    dropped, expected_dropped : int, float
        Samples without a direction, observed and expected.
    pdf_integral : float
        Integral of ``pdf_fn`` over the sphere.
    statistic, dof, p_value : float, int, float
        Pearson's statistic, degrees of freedom (pooled cells - 1) and p-value.
    significance_per_test : float
        The Sidak-corrected level the p-value is compared with.
    passed : bool or None
        Result of the last ``run``.
    failures : list of str
        Reasons the test failed outright, besides a small p-value.
    message : str
        Human-readable summary of the last ``run``.

    Examples
    --------
    A cosine-weighted hemisphere sampler checked against its own pdf:

    >>> import numpy as np
    >>> def sample(n, seed):
    ...     u = np.random.default_rng(seed).random((n, 2))
    ...     r, phi = np.sqrt(u[:, 0]), 2 * np.pi * u[:, 1]
    ...     return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u[:, 0])], axis=1)
    >>> def pdf(wo):
    ...     return np.maximum(wo[:, 2], 0) / np.pi
    >>> test = ChiSquareTest(sample, pdf, sample_count=100_000)
    >>> test.run()
    True
    """

    def __init__(self, sample_fn: SampleFn, pdf_fn: PdfFn, *, res=31,
                 sample_count: int = 1_000_000, min_expected: float = 5.0,
                 significance: float = 0.01, test_count: int = 1, seed: int = 0,
                 quadrature_order: int = 5):
        if not callable(sample_fn):
            raise ValueError("sample_fn must be callable as sample_fn(n, seed)")
        if not callable(pdf_fn):
            raise ValueError("pdf_fn must be callable as pdf_fn(wo)")
        self.sample_fn = sample_fn
        self.pdf_fn = pdf_fn
        self.res = _resolution(res)
        self.sample_count = positive_int("sample_count", sample_count)
        self.min_expected = check.real_scalar("min_expected", min_expected, 0.0, lo_open=True)
        self.significance = check_significance(significance)
        self.test_count = positive_int("test_count", test_count)
        self.seed = check.seed(seed)
        self.quadrature_order = positive_int("quadrature_order", quadrature_order)
        self.significance_per_test = sidak_significance(self.significance, self.test_count)

        self.histogram: np.ndarray | None = None
        self.expected: np.ndarray | None = None
        self.dropped = 0
        self.expected_dropped = float("nan")
        self.pdf_integral = float("nan")
        self.statistic = float("nan")
        self.dof = 0
        self.p_value = float("nan")
        self.pooled_in = 0
        self.passed: bool | None = None
        self._sample_failures: list[str] = []
        self._pdf_failures: list[str] = []
        self.failures: list[str] = []
        self.message = "not run yet"

    # -- the two tables -----------------------------------------------------------------
    def tabulate_histogram(self) -> np.ndarray:
        """Draw ``sample_count`` samples and count them per cell; sets ``histogram``
        and ``dropped``."""
        n = self.sample_count
        wo = np.asarray(self.sample_fn(n, self.seed), dtype=np.float64)
        if wo.shape != (n, 3):
            raise ValueError(f"sample_fn(n, seed) must return an array of shape ({n}, 3), "
                             f"got {wo.shape}")
        self._sample_failures = []
        no_direction = np.any(np.isnan(wo), axis=1) | np.all(wo == 0.0, axis=1)
        length = np.linalg.norm(np.where(no_direction[:, None], 1.0, wo), axis=1)
        not_unit = ~no_direction & ~(np.abs(length - 1.0) <= check.UNIT_TOLERANCE)
        if np.any(not_unit):
            first = int(np.argmax(not_unit))
            self._sample_failures.append(
                f"{int(not_unit.sum())} samples are not unit vectors (row {first} has "
                f"length {length[first]:.6g}); they were left out of the histogram")
        keep = ~no_direction & ~not_unit
        index = _cell_index(wo[keep], self.res)
        counts = np.bincount(index, minlength=self.res[0] * self.res[1])
        self.histogram = counts.reshape(self.res).astype(np.float64)
        self.dropped = int(no_direction.sum())
        return self.histogram

    def tabulate_expected(self) -> np.ndarray:
        """Integrate ``pdf_fn`` over every cell; sets ``expected``, ``pdf_integral``
        and ``expected_dropped``."""
        n_theta, n_phi = self.res
        q = self.quadrature_order
        cos_nodes, cos_weights = _cos_theta_quadrature(n_theta, q)    # (n_theta, 2q)
        phi_edges = np.linspace(-np.pi, np.pi, n_phi + 1)
        phi_nodes, phi_weights = _gauss_legendre(phi_edges[:-1], phi_edges[1:], q)  # (n_phi, q)
        wo = directions_from_cos_phi(cos_nodes[:, :, None, None], phi_nodes[None, None, :, :])
        points = wo.reshape(-1, 3)
        pdf = np.asarray(self.pdf_fn(points), dtype=np.float64)
        if pdf.size != len(points):
            raise ValueError(f"pdf_fn(wo) must return one value per direction: got "
                             f"{pdf.size} values for {len(points)} directions")
        pdf = pdf.reshape(wo.shape[:-1])
        self._pdf_failures = []
        if not np.all(np.isfinite(pdf)):
            self._pdf_failures.append(f"pdf_fn returned {int(np.sum(~np.isfinite(pdf)))} "
                                      "non-finite values")
        if np.any(pdf < 0):
            self._pdf_failures.append(f"pdf_fn returned negative values (min {pdf.min():.3g})")
        pdf = np.where(np.isfinite(pdf), np.maximum(pdf, 0.0), 0.0)
        # Tensor-product rule: sum over the nodes of each cell, axis by axis.
        probability = np.einsum("iajb,ia,jb->ij", pdf, cos_weights, phi_weights)
        self.pdf_integral = float(probability.sum())
        if self.pdf_integral > 1.0 + PDF_INTEGRAL_TOLERANCE:
            self._pdf_failures.append(f"the pdf integrates to {self.pdf_integral:.6f} > 1 "
                                      "over the sphere")
        self.expected = self.sample_count * probability
        missing = 1.0 - self.pdf_integral
        # A shortfall at quadrature-rounding level means "no failures allowed", so that
        # failed samples are then reported as such rather than only via the statistic.
        self.expected_dropped = (self.sample_count * missing if missing > QUADRATURE_ROUNDING
                                 else 0.0)
        return self.expected

    # -- the test -----------------------------------------------------------------------
    def run(self) -> bool:
        """Tabulate (if not done yet) and test; returns True if the sampler is accepted.

        Also sets ``statistic``, ``dof``, ``p_value``, ``passed``, ``failures`` and
        ``message``.
        """
        if self.histogram is None:
            self.tabulate_histogram()
        if self.expected is None:
            self.tabulate_expected()
        failures = self._sample_failures + self._pdf_failures

        observed = np.append(self.histogram.ravel(), self.dropped)
        expected = np.append(self.expected.ravel(), self.expected_dropped)
        impossible = (expected == 0) & (observed > 0)
        if np.any(impossible[:-1]):
            failures.append(f"{int(observed[:-1][impossible[:-1]].sum())} samples fell in "
                            f"{int(impossible[:-1].sum())} cells with expected frequency 0 "
                            "(the pdf is zero there)")
        if impossible[-1]:
            failures.append(f"{self.dropped} samples produced no direction, but the pdf "
                            f"integrates to {self.pdf_integral:.6f} and so allows no failures")

        result = pearson_chi2(observed, expected, self.min_expected)
        self.statistic, self.dof, self.p_value = result.statistic, result.dof, result.p_value
        self.pooled_in = result.pooled_in
        if np.any(impossible):  # impossible under the hypothesis: certain rejection
            self.statistic, self.p_value = float("inf"), 0.0
        if self.dof < 1:
            failures.append("fewer than two cells have data, so there is nothing to test "
                            "(is the pdf zero everywhere? raise sample_count?)")

        self.failures = failures
        self.passed = bool(not failures and np.isfinite(self.p_value)
                           and self.p_value >= self.significance_per_test)
        self.message = self._summary()
        return self.passed

    def plot(self, path):
        """Write a PNG of observed, expected and observed - expected counts over the
        (phi, cos theta) grid; tabulates first if needed. Returns the path written."""
        from bsdflab.testing._plot import plot_observed_expected

        if self.histogram is None:
            self.tabulate_histogram()
        if self.expected is None:
            self.tabulate_expected()
        verdict = {None: "not run", True: "accepted", False: "rejected"}[self.passed]
        title = (f"chi-square test, {self.sample_count} samples: {verdict}"
                 + (f" (p = {self.p_value:.3g})" if np.isfinite(self.p_value) else ""))
        return plot_observed_expected(self.histogram, self.expected, path, title)

    def _summary(self) -> str:
        n_theta, n_phi = self.res
        lines = [
            f"chi-square test of {self.sample_count} samples on a {n_theta} x {n_phi} "
            f"(cos theta, phi) grid",
            f"  samples without a direction: {self.dropped} "
            f"(expected {self.expected_dropped:.1f})",
            f"  pdf integral over the sphere: {self.pdf_integral:.6f}",
            f"  pooled {self.pooled_in} cells with expected count < {self.min_expected:g} "
            "into one",
            f"  chi^2 = {self.statistic:.2f}, dof = {self.dof}, p-value = {self.p_value:.4g}",
            f"  significance {self.significance:g}, Sidak-corrected for {self.test_count} "
            f"test(s): {self.significance_per_test:.4g}",
        ]
        lines += [f"  failure: {reason}" for reason in self.failures]
        if self.failures:
            lines.append("FAILED: see the failures above")
        elif self.passed:
            lines.append("ACCEPTED: the samples are consistent with the pdf")
        else:
            lines.append(f"REJECTED: the samples do not follow the pdf (p-value "
                         f"{self.p_value:.4g} < {self.significance_per_test:.4g})")
        return "\n".join(lines)


def bsdf_chi2(bsdf, wi, *, lobes: Lobe | int = Lobe.ALL, significance: float = 0.01,
              test_count: int = 1, sample_count: int = 1_000_000, seed: int = 0,
              res=31, min_expected: float = 5.0, quadrature_order: int = 5) -> ChiSquareTest:
    """A ``ChiSquareTest`` of ``bsdf.sample`` against ``bsdf.pdf`` for one incident
    direction (not yet run: call ``.run()``).

    Samples from delta lobes are counted as "no direction", because the pdf of a delta
    lobe is not a density; the test then checks that they occur as often as the smooth
    pdf leaves room for (1 minus its integral).

    Parameters
    ----------
    bsdf : bsdflab.BSDF or any object with ``sample`` and ``pdf`` of the same signature
        The BSDF under test.
    wi : array_like, shape (3,)
        Incident direction, unit length, local frame (+z normal).
    lobes : Lobe
        Lobes to sample and evaluate. At least one must be non-delta.
    significance, test_count, sample_count, seed, res, min_expected, quadrature_order
        As for ``ChiSquareTest``. Raise ``quadrature_order`` for very peaked lobes (e.g.
        GGX alpha < 0.1), whose per-cell integrals the default order underestimates.

    Returns
    -------
    ChiSquareTest

    Raises
    ------
    ValueError
        If every selected lobe of ``bsdf`` is a delta lobe (use ``discrete_choice_chi2``).

    Examples
    --------
    >>> import bsdflab
    >>> test = bsdf_chi2(bsdflab.Diffuse(0.5), [0.6, 0.0, 0.8], sample_count=100_000)
    >>> test.run()
    True
    """
    w = single_direction("wi", wi)
    mask = check.lobe_mask(lobes)
    has_lobes = getattr(bsdf, "lobes", None)
    if has_lobes is not None and int(has_lobes) & mask & int(Lobe.SMOOTH) == 0:
        raise ValueError(f"{bsdf!r} has no non-delta lobe among lobes={Lobe(mask)!r}: its pdf "
                         "is zero everywhere and the direction test does not apply; test the "
                         "lobe choice with discrete_choice_chi2 instead")
    delta = int(Lobe.DELTA)

    def sample_fn(n: int, seed: int) -> np.ndarray:
        s = bsdf.sample(np.tile(w, (n, 1)), seed=seed, lobes=mask)
        wo = np.array(s.wo, dtype=np.float64)
        lobe = np.asarray(s.lobe).astype(np.int64)
        wo[(lobe == 0) | ((lobe & delta) != 0)] = np.nan
        return wo

    def pdf_fn(wo: np.ndarray) -> np.ndarray:
        return bsdf.pdf(w, wo, lobes=mask)

    return ChiSquareTest(sample_fn, pdf_fn, res=res, sample_count=sample_count,
                         min_expected=min_expected, significance=significance,
                         test_count=test_count, seed=seed, quadrature_order=quadrature_order)


# -- grid geometry ----------------------------------------------------------------------
def _resolution(res) -> tuple[int, int]:
    if isinstance(res, (int, np.integer)) and not isinstance(res, bool):
        res = (int(res), 2 * int(res))
    try:
        n_theta, n_phi = (int(r) for r in res)
        ok = all(isinstance(r, (int, np.integer)) and not isinstance(r, bool) for r in res)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"res must be an int or a pair of ints (n_theta, n_phi), got {res!r}")
    if n_theta < 3 or n_theta % 2 == 0:
        raise ValueError(f"res: n_theta must be odd and >= 3 (so z = 0 is not a cell "
                         f"boundary), got {n_theta}")
    if n_phi < 1:
        raise ValueError(f"res: n_phi must be >= 1, got {n_phi}")
    return n_theta, n_phi


def _cell_index(wo: np.ndarray, res: tuple[int, int]) -> np.ndarray:
    """Flat cell index (row = cos theta bin, column = phi bin) of unit vectors."""
    n_theta, n_phi = res
    cos_theta = np.clip(wo[:, 2], -1.0, 1.0)
    phi = np.arctan2(wo[:, 1], wo[:, 0])
    row = np.clip(np.floor((cos_theta + 1.0) * 0.5 * n_theta), 0, n_theta - 1).astype(np.int64)
    col = np.clip(np.floor((phi + np.pi) / (2.0 * np.pi) * n_phi), 0, n_phi - 1).astype(np.int64)
    return row * n_phi + col


def _gauss_legendre(lo: np.ndarray, hi: np.ndarray, q: int) -> tuple[np.ndarray, np.ndarray]:
    """q-point Gauss-Legendre nodes and weights on each interval [lo_i, hi_i]."""
    x, w = np.polynomial.legendre.leggauss(q)
    half = 0.5 * (hi - lo)[:, None]
    return 0.5 * (hi + lo)[:, None] + half * x, half * w


def _cos_theta_quadrature(n_theta: int, q: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights on every cos(theta) row, each row split in two; the horizon
    row is split at exactly 0 so neither half straddles the usual pdf jump there."""
    edges = np.linspace(-1.0, 1.0, n_theta + 1)
    lo, hi = edges[:-1], edges[1:]
    split = np.where((lo < 0.0) & (hi > 0.0), 0.0, 0.5 * (lo + hi))
    nodes_lo, weights_lo = _gauss_legendre(lo, split, q)
    nodes_hi, weights_hi = _gauss_legendre(split, hi, q)
    return np.hstack([nodes_lo, nodes_hi]), np.hstack([weights_lo, weights_hi])
