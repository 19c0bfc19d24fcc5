"""Coverage of the per-pair standard error of ``Layered.estimate`` / ``eval_with_error``
against adding-doubling (issue 32, docs/coverage.md "Per pair").

A stated standard error is honest when |PFMC - AD| exceeds k of it about as often as a
normal deviate does, 2 (1 - Phi(k)). Per seed, 24 fixed random direction pairs at the
model's default effort (256 walks, scattered part); one channel per pair ((seed + pair)
mod 3: channels of a pair share walks, so the counted pairs are independent and each count
is binomial). z = (PFMC - AD) / hypot(PFMC error, AD bound). Per k = 2, 3, 4 the count
must lie in the two-sided binomial acceptance region, Sidak-corrected over the three k
(family alpha 0.01, per-k alpha 0.00334).

Power: the same estimates with ``error_walks=0`` (the value's own walks' spread, the error
before the option; equivalently the mutation "estimate_pooled ignores error_walks") fail
the same criterion at these seeds, asserted in test 01: snake k = 3 holds 23 of 1440
against the acceptance bound of 11 (k = 2: 95, bound 90); plastic
with pfmc k = 2: 93 (bound 90). The default: snake 84, 9, 0 beyond k = 2, 3, 4; plastic
78, 3, 0. The mutation "error_seed returns the seed" (error walks that repeat the value's)
passes the coverage tests (83, 7, 0 and 81, 4, 0: pooling with the value's own walks is close
to the design) and fails test 00, which catches it exactly.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import bsdflab as bl
from bsdflab.presets import preset
from bsdflab.solvers import solve
from bsdflab.testing import random_unit_vectors, sidak_significance

WL = [450.0, 550.0, 650.0]
KS = (2.0, 3.0, 4.0)
PAIRS = 24
SAMPLES = 256


def snake(estimator: str = "pfmc2"):
    return bl.from_dict({**preset("xenopeltis").to_dict(), "estimator": estimator})


def plastic(estimator: str = "pfmc2"):
    return bl.Layered(
        [bl.Dielectric(1.5)], [bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0)], bl.Diffuse(0.6), estimator=estimator
    )


def directions():
    return (
        random_unit_vectors(PAIRS, seed=11, hemisphere="upper"),
        random_unit_vectors(PAIRS, seed=12, hemisphere="upper"),
    )


_REFERENCES = {}


def reference(model):
    """Adding-doubling's (value, bound) at ``directions()``, solved once per model (test_01
    asks twice for the snake's: ~3.7 CPU-s a solve)."""
    key = repr(model.to_dict())
    if key not in _REFERENCES:
        _REFERENCES[key] = solve(model, WL).eval_with_error(*directions(), scattered_only=True)
    return _REFERENCES[key]


def z_scores(model, seeds, error_walks=None) -> np.ndarray:
    """One channel's z per seed and pair (the estimate's stated error, AD's bound added)."""
    wi, wo = directions()
    ref, ref_err = reference(model)
    rows = np.arange(PAIRS)
    zs = []
    for seed in seeds:
        e = model.estimate(wi, wo, WL, samples=SAMPLES, seed=int(seed), scattered_only=True, error_walks=error_walks)
        z = (e.value - ref) / np.hypot(e.stderr, ref_err)
        zs.append(z[rows, (seed + rows) % len(WL)])
    return np.concatenate(zs)


def miscovered(z) -> list[str]:
    """The k whose count of |z| > k falls outside its binomial acceptance region."""
    alpha = sidak_significance(0.01, len(KS))
    bad = []
    for k in KS:
        p0 = 2 * stats.norm.sf(k)
        lo, hi = stats.binom.ppf(alpha / 2, z.size, p0), stats.binom.isf(alpha / 2, z.size, p0)
        count = int(np.count_nonzero(np.abs(z) > k))
        if not lo <= count <= hi:
            bad.append(f"k={k:g}: {count} of {z.size} beyond (acceptance {lo:.0f}..{hi:.0f})")
    return bad


def test_00_error_walks_leave_the_value_unchanged():
    """The extra walks serve the error alone: the value is eval's, bit for bit, whatever
    error_walks is; the error changes; bad input is a ValueError."""
    model = snake()
    wi, wo = directions()
    runs = [model.estimate(wi, wo, WL, error_walks=m) for m in (None, 0, 1, 4096)]
    for r in runs:
        assert np.array_equal(r.value, model.eval(wi, wo, WL)) and r.nonfinite == 0
    assert not np.array_equal(runs[0].stderr, runs[1].stderr)
    # error walks from the value's own seed would repeat its walks: as many of them would
    # pool to the same error, bit for bit (the mutation "error_seed returns the seed")
    same = model.estimate(wi, wo, WL, error_walks=model.samples)
    assert not np.allclose(same.stderr, runs[1].stderr, rtol=1e-3, atol=0)
    value, err = model.eval_with_error(wi, wo, WL, error_walks=0)
    assert np.array_equal(err, runs[1].stderr) and np.array_equal(value, runs[1].value)
    for bad in (-1, 1.5, "4"):
        with pytest.raises(ValueError, match="error_walks"):
            model.estimate(wi, wo, WL, error_walks=bad)


def test_01_default_error_covers_the_snake():
    """Snake (per-walk skewness 3-6, excess kurtosis 29-86), 60 seeds x 24 pairs: the
    default error covers at k = 2, 3, 4; the value's own spread (error_walks=0) does not.
    pfmc walks the snake exactly as pfmc2 does (docs/estimators.md), so one estimator.
    The reference solve is shared by both runs (``reference``). Mutation: Layered.estimate's
    stderr scaled by 0.8 fails it."""
    model = snake()
    assert miscovered(z_scores(model, range(60))) == []
    old = miscovered(z_scores(model, range(60), error_walks=0))
    assert any(b.startswith("k=3") for b in old), old


def test_02_default_error_covers_plastic_pfmc():
    """Plastic (kurtosis ~12) with the reference estimator pfmc, whose walks differ from
    pfmc2's there: 60 seeds x 24 pairs."""
    assert miscovered(z_scores(plastic("pfmc"), range(60))) == []


@pytest.mark.slow
@pytest.mark.parametrize("estimator", ["pfmc2", "pfmc"])
@pytest.mark.parametrize("make", [snake, plastic], ids=["snake", "plastic"])
def test_03_study_200_seeds(make, estimator):
    """The study's pair rows (bench/coverage_tables.py --what pairs): 200 seeds, 4 800 pairs."""
    assert miscovered(z_scores(make(estimator), range(200))) == []
