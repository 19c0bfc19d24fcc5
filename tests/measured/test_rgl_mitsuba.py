"""RGL files written by bsdflab, read by Mitsuba 3's own ``measured`` plugin and by
``bl.Measured``: the two readers agree to float32 round-off, both stay within the writer's
reported error bound of the source model, and both samplers pass a chi^2 test.

The source is a rough gold conductor (deterministic, analytic): RGB through the reference
variant (llvm_ad_rgb or scalar_rgb, reference/mitsuba_env.py) and spectral through
scalar_spectral. Tolerances: Mitsuba computes in float32, so eval and pdf at the same
float32 directions agree to ~1e-5 relative (FLOAT32_REL = 1e-4 leaves room); sampling
chains two quadratic inversions in float32, so its pdf gets 1e-2 (and 1e-4 at the 99th
percentile).
"""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import Measured, export_model
from bsdflab.measured.rgl import random_pairs
from bsdflab.reference.mitsuba_calls import query
from bsdflab.testing import ChiSquareTest, bsdf_chi2

pytestmark = pytest.mark.mitsuba

FLOAT32_REL = 1e-4
SIGNIFICANCE = 0.01
N = 1500
OPTIONS = {"n_theta_i": 8, "resolution": 24, "error_points": 4000}
SPECTRAL_NM = np.linspace(420.0, 680.0, 6)


@pytest.fixture(scope="module")
def gold(tmp_path_factory):
    path = tmp_path_factory.mktemp("rgl") / "gold.bsdf"
    model = RoughConductor(alpha=0.25, material="Au")
    report = export_model(model, path, **OPTIONS)
    return model, path, report


@pytest.fixture(scope="module")
def gold_spectral(tmp_path_factory):
    path = tmp_path_factory.mktemp("rgl") / "gold_spec.bsdf"
    model = RoughConductor(alpha=0.25, material="Au")
    report = export_model(model, path, wavelengths=SPECTRAL_NM, **OPTIONS)
    return model, path, report


def _f32(a):
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def _queries(measured, seed):
    rng = np.random.default_rng(seed)
    wi, wo = random_pairs(measured.reference, N, rng)
    return _f32(wi), _f32(wo), rng.random(N), _f32(rng.random((N, 2)))


def _close(a, b, rel, what):
    scale = np.maximum(np.abs(b), 1e-3 * np.abs(b).max())
    worst = float(np.max(np.abs(a - b) / scale))
    assert worst <= rel, f"{what}: largest relative difference {worst:.3g} > {rel:g}"
    return worst


def test_01_mitsuba_loads_and_agrees_rgb(gold):
    _, path, _ = gold
    ours = Measured(path)
    wi, wo, u1, u2 = _queries(ours, 1)
    theirs = query({"type": "measured", "filename": str(path)}, wi, wo, u1, u2)
    _close(theirs.eval, ours.eval(wi, wo), FLOAT32_REL, "eval")
    _close(theirs.pdf, ours.pdf(wi, wo), FLOAT32_REL, "pdf")
    s = ours.sample(wi, u1, u2)
    both = (s.pdf > 0) & np.any(theirs.sample_weight != 0, axis=1)
    assert both.mean() > 0.8
    assert np.abs(s.wo - theirs.sample_wo)[both].max() < 1e-3
    rel = np.abs(s.pdf - theirs.sample_pdf)[both] / s.pdf[both]
    assert rel.max() < 1e-2 and np.quantile(rel, 0.99) < 1e-4


def test_02_mitsuba_agrees_spectral(gold_spectral):
    import mitsuba as mi

    _, path, _ = gold_spectral
    ours = Measured(path)
    wi, wo, u1, u2 = _queries(ours, 2)
    lam = np.random.default_rng(3).uniform(SPECTRAL_NM[0], SPECTRAL_NM[-1], N)
    previous = mi.variant()
    mi.set_variant("scalar_spectral")
    try:
        theirs = query({"type": "measured", "filename": str(path)}, wi[:300], wo[:300], u1[:300], u2[:300],
                       wavelengths=lam[:300])
    finally:
        mi.set_variant(previous)
    # bl.Measured interpolates between the file's wavelengths as Mitsuba does.
    mine = np.array([ours.eval(wi[k:k + 1], wo[k:k + 1], wavelengths=[_f32(lam[k])])[0, 0] for k in range(300)])
    _close(theirs.eval[:, 0], mine, FLOAT32_REL, "spectral eval")
    _close(theirs.pdf, ours.pdf(wi[:300], wo[:300]), FLOAT32_REL, "spectral pdf")


@pytest.mark.parametrize("which", ["gold", "gold_spectral"])
def test_03_within_the_reported_bound(which, request):
    """Fresh random pairs (another seed than the writer's): both readers within the bound
    the writer reported against the source model."""
    model, path, report = request.getfixturevalue(which)
    ours = Measured(path)
    wi, wo, u1, u2 = _queries(ours, 11)
    keep = (wi[:, 2] > np.sin(np.radians(0.5))) & (wo[:, 2] > np.sin(np.radians(0.5)))
    wi, wo = wi[keep], wo[keep]
    wl = None if which == "gold" else ours.data.wavelengths.astype(float)
    source = model.eval(wi, wo, wavelengths=wl)
    mine = ours.eval(wi, wo, wavelengths=wl)
    assert np.abs(mine - source).max() <= report.bound
    if which == "gold":
        theirs = query({"type": "measured", "filename": str(path)}, wi, wo, u1[keep], u2[keep])
        assert np.abs(theirs.eval - source).max() <= report.bound * (1 + FLOAT32_REL)


@pytest.mark.parametrize("theta_deg", [0.0, 40.0, 80.0])
def test_04_chi2_ours(gold, theta_deg):
    _, path, _ = gold
    t = np.radians(theta_deg)
    test = bsdf_chi2(Measured(path), [np.sin(t), 0.0, np.cos(t)], significance=SIGNIFICANCE,
                     test_count=6, sample_count=200_000)
    assert test.run(), test.messages if hasattr(test, "messages") else "chi2 failed"


@pytest.mark.parametrize("theta_deg", [0.0, 40.0, 80.0])
def test_05_chi2_mitsuba(gold, theta_deg):
    """Mitsuba's own sampler against Mitsuba's own pdf, on our file."""
    _, path, _ = gold
    plugin = {"type": "measured", "filename": str(path)}
    t = np.radians(theta_deg)
    wi = np.array([np.sin(t), 0.0, np.cos(t)])

    def sample_fn(n, seed):
        rng = np.random.default_rng(seed)
        r = query(plugin, np.tile(wi, (n, 1)), np.tile(wi, (n, 1)), rng.random(n), rng.random((n, 2)))
        wo = r.sample_wo.copy()
        wo[~np.any(r.sample_weight != 0, axis=1)] = np.nan
        return wo

    def pdf_fn(wo):
        return query(plugin, np.tile(wi, (len(wo), 1)), wo, np.zeros(len(wo)), np.zeros((len(wo), 2))).pdf

    test = ChiSquareTest(sample_fn, pdf_fn, sample_count=200_000, significance=SIGNIFICANCE, test_count=6)
    assert test.run()
