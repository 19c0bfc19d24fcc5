"""Review of the layered estimator pfmc2 (docs/estimators.md, "A second layered estimator").

pfmc2 lets up to four walks share one light chain and computes the standard error over
the groups (a chain and its walks), which is right for correlated walks. With `samples`
<= 4 there is one group, and the error of one sample is reported as 0: a stochastic
estimate claims to be exact. pfmc (one walk per chain) reports a positive error from
`samples` >= 2 walks. The tabulator reads that error to decide how many walks a cell
needs (`Tabulator::effort`): with min_samples <= 4 every pilot error is 0, no cell is
refined, and the table's meta records an achieved error of 0.

Tests 01-02 are deterministic (an error of exactly 0 from a sample whose values vary
with the seed), so they need no significance level. Test 03 guards what pfmc2 gets right:
its reported error covers the correlation of walks that share a chain. Over R
independent estimates per pair, the spread of the values (sample variance) must match
the mean reported variance; the ratio's standard error is sqrt((kurtosis - 1) / R) (the
sample variance's, kurtosis measured), two-sided at family-wise ALPHA = 0.01, Sidak over
the pairs. Power: a rough top (alpha 0.3, the widest exit pfmc2 still shares chains
through) over a clear slab, where the chain carries much of the walks' spread; in a clear
slab pfmc2's walks are pfmc's walks (no bright slab), so pfmc's reported error is what a
per-walk error would read for pfmc2 (test 03b measures how far that is off).

Since estimator version 6 pfmc2 shares no chain through an exit rougher than alpha 0.3
(a wide exit lobe made the shared chain cost more than it saved, 0.51x at alpha 0.8):
test 04 checks that such a stack with no bright slab gives pfmc's numbers bit for bit.
"""
import numpy as np

import bsdflab as bl
from bsdflab.tables import TableGrid, tabulate
from bsdflab.testing import random_unit_vectors, sidak_z_limit

WL = [550.0]
ALPHA = 0.01


def _model(estimator):
    # A rough top (its chain is random: walks sharing it are correlated) over a
    # scattering slab and a diffuse base.
    return bl.Layered([bl.RoughDielectric(0.3, 1.5, 1.0)], [bl.Slab(0.5, sigma_a=0.3, sigma_s=2.0)],
                      bl.Diffuse(0.8), estimator=estimator)


def test_01_a_few_walks_report_a_positive_standard_error():
    wi = random_unit_vectors(4, seed=1, hemisphere="upper")
    wo = random_unit_vectors(4, seed=2, hemisphere="upper")
    for estimator in ("pfmc", "pfmc2"):
        m = _model(estimator)
        for n in (2, 3, 4):
            a = m.estimate(wi, wo, wavelengths=WL, samples=n, seed=3)
            b = m.estimate(wi, wo, wavelengths=WL, samples=n, seed=4)
            assert np.all(a.value != b.value), (estimator, n)  # the estimate is random ...
            assert np.all(a.stderr > 0), (estimator, n, a.stderr[:, 0])  # ... so is not exact


def test_02_a_table_with_a_small_pilot_reports_its_error():
    grid = TableGrid(3, 3, 3)
    for estimator in ("pfmc", "pfmc2"):
        t = tabulate(_model(estimator), grid, rel_error=0.05, wavelengths=WL, min_samples=4,
                     max_samples=1 << 16, progress=False)
        assert float(np.max(t.stderr)) > 0 and t.meta["rel_error_rms"] > 0, (estimator, t.meta)
        assert int(t.samples.max()) > 4, estimator  # the pilot's error asked for refinement


def test_03_the_reported_error_covers_walks_sharing_a_chain():
    pairs, replicates, walks = 4, 600, 64
    m = _shared_chain_model("pfmc2")
    z, _ = _spread_against_reported(m, m, pairs, replicates, walks)
    assert np.max(np.abs(z)) < sidak_z_limit(ALPHA, pairs), z


def test_03b_power_a_per_walk_error_would_be_rejected():
    # pfmc's reported error on the same walks' model is per walk: against pfmc2's spread it
    # must read low by far more than the test's limit (else test 03 could not fail).
    pairs, replicates, walks = 4, 600, 64
    z, ratio = _spread_against_reported(_shared_chain_model("pfmc2"), _shared_chain_model("pfmc"), pairs,
                                        replicates, walks)
    assert np.min(ratio) > 1.2 and np.min(z) > sidak_z_limit(ALPHA, pairs), (ratio, z)


def test_04_no_shared_chain_through_a_wide_exit():
    wi = random_unit_vectors(6, seed=3, hemisphere="upper")
    wo = random_unit_vectors(6, seed=4, hemisphere="upper")
    wide = {e: bl.Layered([bl.RoughDielectric(0.8, 1.5)], [bl.Slab(0.1)], bl.Diffuse(0.8), estimator=e)
            for e in ("pfmc", "pfmc2")}
    a, b = (wide[e].estimate(wi, wo, wavelengths=WL, samples=64, seed=9) for e in ("pfmc", "pfmc2"))
    assert np.array_equal(a.value, b.value) and np.array_equal(a.stderr, b.stderr)
    narrow = {e: _shared_chain_model(e) for e in ("pfmc", "pfmc2")}
    a, b = (narrow[e].estimate(wi, wo, wavelengths=WL, samples=64, seed=9) for e in ("pfmc", "pfmc2"))
    assert not np.array_equal(a.value, b.value)  # alpha 0.3: chains shared


def _shared_chain_model(estimator):
    return bl.Layered([bl.RoughDielectric(0.3, 1.5)], [bl.Slab(0.1)], bl.Diffuse(0.8), estimator=estimator)


def _spread_against_reported(spread_model, error_model, pairs, replicates, walks):
    """z of (variance of spread_model's values / error_model's mean reported variance - 1)."""
    wi = random_unit_vectors(pairs, seed=1, hemisphere="upper")
    wo = random_unit_vectors(pairs, seed=2, hemisphere="upper")
    runs = [spread_model.estimate(wi, wo, wavelengths=WL, samples=walks, seed=1000 + r) for r in range(replicates)]
    v = np.array([e.value[:, 0] for e in runs])
    errors = runs if error_model is spread_model else [
        error_model.estimate(wi, wo, wavelengths=WL, samples=walks, seed=5000 + r) for r in range(replicates)]
    reported = np.mean([e.stderr[:, 0] ** 2 for e in errors], axis=0)
    ratio = v.var(axis=0, ddof=1) / reported
    kurtosis = np.mean((v - v.mean(axis=0)) ** 4, axis=0) / v.var(axis=0) ** 2
    return (ratio - 1.0) / np.sqrt((kurtosis - 1.0) / replicates), ratio
