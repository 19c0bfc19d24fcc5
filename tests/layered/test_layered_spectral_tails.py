"""Spectral throughput whose channels differ wildly, in long walks (review of issue 21,
defect 4: roulette without a depth cap makes walks in bright slabs long).

A thick bright slab (sigma_s 10 /um, 1 um) over a white base, with sigma_a 0.001 /um at
450 nm (single-scattering albedo 0.9999) and 5 /um at 650 nm. Reference: the
adding-doubling oracle (~1e-5 relative). z-tests at family-wise ALPHA = 0.01, Sidak over
the pairs plus the pooled mean z.

1. One channel at a time the estimate agrees (the control: model, oracle and roulette).
2. Both channels in one estimate: the bright channel must still agree. It does not today
   (strict xfail): `fly` draws each flight with a channel picked per flight (one-sample
   spectral MIS per flight), so each collision multiplies the bright channel's throughput
   by a factor between ~0.8 and ~2; over the walk's hundreds of collisions the product is
   heavy-tailed (sample() weights up to ~2400 where the single-channel walk never
   exceeds 1; the top 0.1 % of walks carry 11 % of the mass). The estimate reads
   -6.7 % at 20 000 walks per pair (pooled z -7), -6.2 % at 100 000 (z -8), with a
   reported error that does not cover it. Version 4's 256-event cap hid part of it
   (-13.6 %, cap bias included). A fix: choose the hero channel once per walk and weight
   the path by the balance heuristic over the channels' path densities (Wilkie et al.
   2014, hero wavelength sampling), which bounds the weights by the channel count.
   Fixed by estimator="pfmc2" (issue 21; the default since estimator version 6): in a
   slab this bright every flight is drawn with the smallest extinction, so each channel's
   weight is <= 1 per flight and the product never grows (docs/estimators.md). The
   reference estimator="pfmc" still reads low here (the test's power: with it the check fails, pooled z -6.2).
"""
import numpy as np

import bsdflab as bl
from bsdflab.oracles import AddingDoublingOracle
from bsdflab.testing import random_unit_vectors, sidak_z_limit

ALPHA = 0.01
PAIRS = 8
WALKS = 20_000
CONTROL_WALKS = 10_000  # test_01 (its docstring)
SIGMA_A = {"type": "tabulated", "wavelengths": [450.0, 650.0], "values": [0.001, 5.0]}


def _model(estimator="pfmc2"):
    return bl.Layered([bl.Dielectric(1.5)], [bl.Slab(1.0, sigma_a=SIGMA_A, sigma_s=10.0)],
                      bl.Diffuse(1.0), estimator=estimator)


def _z_bright_channel(wavelengths, walks=WALKS):
    m = _model()
    wi = random_unit_vectors(PAIRS, seed=71, hemisphere="upper")
    wo = random_unit_vectors(PAIRS, seed=72, hemisphere="upper")
    e = m.estimate(wi, wo, wavelengths=wavelengths, samples=walks, seed=73)
    ref, ref_err = AddingDoublingOracle.from_layered(m).eval_with_error(wi, wo, wavelengths=wavelengths)
    assert e.capped == 0 and e.nonfinite == 0
    z = ((e.value - ref) / np.hypot(e.stderr, ref_err))[:, 0]  # 450 nm
    return z, z.mean() * np.sqrt(PAIRS)


def _check(z, pooled):
    limit = sidak_z_limit(ALPHA, 2 * (PAIRS + 1))
    assert np.max(np.abs(z)) < limit and abs(pooled) < limit, (z, pooled)


def test_01_one_channel_at_a_time_agrees():
    """The control at 10 000 walks per pair (test_02 needs 20 000 for its power against
    pfmc; the control's z takes the estimate's own error): a 2 % bias still reads pooled z
    6.7 (max 4.2) against the limit 3.45. Mutation: Layered.estimate's value scaled by
    1.02 fails it."""
    _check(*_z_bright_channel([450.0], walks=CONTROL_WALKS))


def test_02_bright_channel_next_to_an_absorbed_one_agrees():
    _check(*_z_bright_channel([450.0, 650.0]))
