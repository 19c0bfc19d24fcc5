"""The body colour is fitted to the layered model's scattered albedo.

Synthetic case with a closed form: a smooth dielectric (n = 1.5, no film) over a grey
Lambertian base (rho = 0.6), no absorption in between. Light that enters (1 - F(theta_i))
bounces between base and interface; a Lambertian field meets the interface from inside and
escapes with 1 - r_i, r_i = 1 - (1 - r_e) / n^2 the internal diffuse reflectance (r_e the
external one, 2 int F(mu) mu d mu). So the scattered albedo is exactly
(1 - F(theta_i)) rho (1 - r_i) / (1 - rho r_i): a target that layers by albedo scaling
(C (1 - F)) holds it with C = rho (1 - r_i) / (1 - rho r_i), whatever the angle.
Fresnel here is written out independently of the C++ core.

Tolerance: the walks' standard error of the albedo (propagated to C, at most the largest
per-angle error) times z = 4 (alpha ~ 1e-4 per channel, Sidak over 3 channels ~ 2e-4),
plus 0.002 for the (1 - F) fit of the target's (refitted) base index.
Mutation tried: the albedo without the 2 pi of the hemisphere integral fails.
"""
from __future__ import annotations

import numpy as np

from bsdflab.export import export

N, RHO = 1.5, 0.6
MODEL = {"type": "layered", "interfaces": [{"type": "dielectric", "ext_ior": 1.0, "int_ior": N}],
         "slabs": [{"thickness_um": 0.0}], "base": {"type": "diffuse", "reflectance": RHO}}


def _fresnel(mu, n):
    """Unpolarised Fresnel reflectance from n = 1 into n at cosine mu."""
    st2 = (1.0 - mu**2) / n**2
    mt = np.sqrt(1.0 - st2)
    rs = (mu - n * mt) / (mu + n * mt)
    rp = (n * mu - mt) / (n * mu + mt)
    return 0.5 * (rs**2 + rp**2)


def _expected_body():
    mu = (np.arange(200000) + 0.5) / 200000
    r_e = 2.0 * np.mean(_fresnel(mu, N) * mu)
    r_i = 1.0 - (1.0 - r_e) / N**2
    return RHO * (1.0 - r_i) / (1.0 - RHO * r_i)


def test_body_colour_recovers_the_closed_form(tmp_path):
    report = export(MODEL, "openpbr", str(tmp_path / "body.mtlx"))
    body = np.array(report["parameters"]["base_color"]["value"])
    b = report["body_delta_e00"]
    assert b is not None and len(b["delta_e00"]) == len(b["angles_deg"]) >= 3
    expected = _expected_body()
    exact = np.array(b["albedo_exact"])
    tol = 4.0 * 0.02 * exact.max() + 0.002   # stderr bound below, checked too
    assert np.all(np.abs(body - expected) <= tol), (body, expected)
    assert b["max"] < 1.0                     # a grey Lambertian under albedo scaling: one colour fits


def test_body_albedo_noise_is_what_the_tolerance_assumes():
    from bsdflab.bsdfs.base import from_dict
    from bsdflab.export.body import scattered_albedo

    albedo, err = scattered_albedo(from_dict(MODEL))
    assert np.all(err <= 0.02 * albedo.max()), err
    through = 1.0 - _fresnel(np.cos(np.radians([0.0, 30.0, 50.0, 70.0])), N)
    np.testing.assert_allclose(albedo, (through * _expected_body())[:, None] * np.ones(3), rtol=0,
                               atol=float(4.0 * err.max() + 1e-3))
