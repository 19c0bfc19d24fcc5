"""Layered.delta_reflectance: the top's delta reflection, and nothing else (issue 21,
defect 2). Version 4 copied the weight of whatever the top's sample returned under the
DELTA_REFLECTION mask, and a rough top leaked a glossy transmission there: xenopeltis gave
0.377 at 0 degrees, 450 nm, where a rough top has no delta lobe at all.

The documented identity: the sampled albedo (mean weight of ``sample``, every lobe) equals
the integral of ``eval`` over the sphere plus ``delta_reflectance`` for stacks whose only
all-delta path is the top's own reflection. Checked for a rough top (delta part 0) and a
smooth one (the Fresnel reflectance) by z-tests at family-wise ALPHA = 0.01, Sidak over
every (model, direction, wavelength).
"""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab.optics import fresnel_reflectance
from bsdflab.testing import albedo_uniform, sidak_z_limit
from support.directions import directions_at

ALPHA = 0.01
WL = [450.0, 600.0]
COSINES = (1.0, 0.4)
MODELS = {
    "xenopeltis (rough film top)": lambda: bl.presets.xenopeltis(samples=16),
    "smooth top over a scattering slab": lambda: bl.Layered(
        [bl.Dielectric(1.5)], [bl.Slab(1.0, sigma_a=0.3, sigma_s=1.0)], bl.Diffuse(0.5), samples=16),
}
FAMILY = len(MODELS) * len(COSINES) * len(WL)


def test_01_rough_top_has_no_delta_reflection():
    m = bl.presets.xenopeltis()
    wi = np.array([directions_at(c) for c in (1.0, 0.7, 0.2, 0.01)])
    assert np.all(m.delta_reflectance(wi, wavelengths=[450.0, 550.0]) == 0)
    assert np.all(m.delta_reflectance(wi) == 0)  # RGB too


def test_02_smooth_top_is_its_fresnel_reflectance():
    m = MODELS["smooth top over a scattering slab"]()
    for c in (1.0, 0.4, 0.05):
        r = m.delta_reflectance(directions_at(c), wavelengths=WL)
        want = fresnel_reflectance(c, m.interfaces[0].ext_ior, 1.5).unpolarised
        assert np.allclose(r, want, rtol=1e-12, atol=0)


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("cos_theta", COSINES)
def test_03_albedo_is_eval_integral_plus_delta_reflectance(name, cos_theta):
    m = MODELS[name]()
    wi = directions_at(cos_theta)
    n = 60_000
    s = m.sample(np.tile(wi, (n, 1)), seed=31, wavelengths=WL)
    sampled, s_err = s.weight.mean(axis=0), s.weight.std(axis=0, ddof=1) / np.sqrt(n)
    u = albedo_uniform(m, wi, n=6000, seed=32, wavelengths=WL)
    total = u.mean + m.delta_reflectance(wi, wavelengths=WL)[0]
    z = (sampled - total) / np.hypot(s_err, u.stderr)
    assert np.max(np.abs(z)) < sidak_z_limit(ALPHA, FAMILY), (sampled, total, z)
