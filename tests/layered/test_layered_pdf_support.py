"""Layered.pdf through a delta exit-side boundary (a smooth top, a smooth transmissive
base): positive wherever sample() returns a direction, zero where it never can.

The walk's exit density through a smooth boundary is not estimated: pdf() spreads the
share of draws that leave through it as a cosine lobe (docs/estimators.md, version 5).
Version 5 as first committed used the raw share k / n of its `pdf_samples` walks (default
1), so pdf() was 0 for ~64 % of a smooth top's own samples (and sample() reported pdf 0
with them: a renderer that drops pdf-0 samples, as pbrt-v4's BSDF::Sample_f does, or an
emitter that light sampling cannot reach, loses them), and it spread the lobe over the
whole hemisphere even where the boundary cannot refract toward wo (an outside denser than
the slab, beyond the critical angle), giving MIS weight to directions sample() never
produces. Now the share is smoothed, (k + 1) / (n + 2), and the lobe is confined to the
directions the boundary refracts into and normalised over them.

Test 03 checks that normalisation: the pdf's integral over the exit side equals the
smoothed share of draws sample() returns through that side (z-test, Sidak-corrected over
its cases at ALPHA = 0.01). Mutation tried: dropping the normalisation (the lobe
integrates to sin^2 of the critical angle, 0.66 and 0.56 here) fails both denser cases.
"""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.testing import sidak_z_limit, spherical_directions

ALPHA = 0.01
WL = [550.0]
SLAB = dict(sigma_a=0.2, sigma_s=1.0)
MODELS = {
    # the common clear coat: smooth top over a scattering slab over a diffuse base
    "smooth top": lambda **kw: bl.Layered([bl.Dielectric(1.5)], [bl.Slab(0.5, **SLAB)],
                                          bl.Diffuse(0.6), **kw),
    # an outside denser than the slab: exits only within the critical cone
    "denser outside": lambda **kw: bl.Layered([bl.Dielectric(1.3, 1.6)], [bl.Slab(0.5, **SLAB)],
                                              bl.Diffuse(0.6), **kw),
    # transmission through a smooth base into a denser medium below
    "denser below": lambda **kw: bl.Layered([bl.Dielectric(1.5)], [bl.Slab(0.5, **SLAB)],
                                            bl.Dielectric(2.0, 1.5), **kw),
}
# (model, sign of the exit side's z, sin^2 of the critical angle on that side)
EXITS = [("smooth top", 1, 1.0), ("denser outside", 1, (1.3 / 1.6) ** 2),
         ("denser below", -1, (1.5 / 2.0) ** 2)]


def _exits(model, wi, n, side, seed=1):
    s = model.sample(np.tile(wi, (n, 1)), seed=seed, wavelengths=WL)
    keep = (s.lobe != 0) & ((s.lobe & int(Lobe.DELTA)) == 0) & (np.sign(s.wo[:, 2]) == side)
    return s, keep


# (at 80 degrees nothing enters the denser-outside stack: total internal reflection)
@pytest.mark.parametrize("name, theta", [(n, t) for n in MODELS for t in (0.0, 40.0, 80.0)
                                         if (n, t) != ("denser outside", 80.0)])
def test_01_sampled_directions_have_positive_pdf(name, theta):
    model = MODELS[name](samples=1)
    wi = spherical_directions(np.radians(theta), 0.3)
    s = model.sample(np.tile(wi, (3000, 1)), seed=2, wavelengths=WL)
    nd = (s.lobe != 0) & ((s.lobe & int(Lobe.DELTA)) == 0)
    assert nd.sum() > 300
    assert np.all(s.pdf[nd] > 0), f"{name}: pdf 0 for {np.mean(s.pdf[nd] == 0):.0%} of sample()'s directions"
    p = model.pdf(np.tile(wi, (int(nd.sum()), 1)), s.wo[nd], wavelengths=WL)
    assert np.array_equal(p, s.pdf[nd])


@pytest.mark.parametrize("name, side, cone", EXITS)
def test_02_pdf_is_zero_where_the_boundary_cannot_refract(name, side, cone):
    model = MODELS[name](samples=1)
    wi = spherical_directions(np.radians(30.0), 0.0)
    s, keep = _exits(model, wi, 20_000, side)
    cos_c = np.sqrt(1.0 - cone)
    assert keep.sum() > 1000 and np.all(np.abs(s.wo[keep, 2]) >= cos_c - 1e-9)
    cz = np.linspace(0.01, 0.99, 99)
    wo = np.stack([np.sqrt(1 - cz ** 2), np.zeros_like(cz), side * cz], axis=1)
    p = model.pdf(np.tile(wi, (len(cz), 1)), wo, wavelengths=WL)
    inside = cz > cos_c + 1e-6
    assert np.all(p[inside] > 0) and np.all(p[cz < cos_c - 1e-6] == 0), (name, p)


@pytest.mark.parametrize("name, side, cone", EXITS)
def test_03_lobe_integrates_to_the_smoothed_exit_share(name, side, cone):
    walks, n_dirs, n_draws = 64, 3000, 20_000
    model = MODELS[name](samples=1, pdf_samples=walks)
    wi = spherical_directions(np.radians(30.0), 0.0)
    _, keep = _exits(model, wi, n_draws, side, seed=3)
    share = keep.mean()
    share_err = keep.std(ddof=1) / np.sqrt(n_draws)
    # uniform directions on the exit side (the smooth top's own reflection has no density)
    rng = np.random.default_rng(4)
    cz, phi = rng.uniform(size=n_dirs), rng.uniform(0, 2 * np.pi, size=n_dirs)
    sz = np.sqrt(1 - cz ** 2)
    wo = np.stack([sz * np.cos(phi), sz * np.sin(phi), side * cz], axis=1)
    values = 2 * np.pi * model.pdf(np.tile(wi, (n_dirs, 1)), wo, wavelengths=WL)
    integral, integral_err = values.mean(), values.std(ddof=1) / np.sqrt(n_dirs)
    expected = (walks * share + 1) / (walks + 2)
    z = (integral - expected) / np.hypot(integral_err, share_err * walks / (walks + 2))
    assert abs(z) < sidak_z_limit(ALPHA, len(EXITS)), (name, integral, expected, z)
