"""Layered PFMC: paths that leave a scattering vertex through delta events only, bouncing at
least once between smooth boundaries (issue #10 follow-up, found by the adding-doubling
oracle). Version 2 of the estimator never counted them: next-event estimation went
straight to the exit and strategy B needs a rough exit-side boundary.

Check: for light from wi, the albedo of eval (wo uniform over each hemisphere: the mean
of 2 pi eval(wi, wo)|cos theta_o|, `estimate` returning eval with its cosine) plus the stack's delta parts
(unscattered light, closed form below) equals the albedo of the sampler's plain random
walk (mean `sample` weight; it has no connections, so it cannot miss a class), in
reflection and in transmission separately. The delta parts come from an independent
adding of scalar Fresnel interfaces and slab transmittances (energy), times the radiance
factor (n_entry / n_exit)^2 that `sample`'s weights carry in transmission; a clear slab
(no scattering, so eval is 0) checks that closed form against the sampler first.

Statistics: eval-albedo and sample-albedo are independent means of >= 3 * 10^4 bounded
terms each (normal to well within the test level); z = difference / hypot of their
standard errors, Sidak-corrected over every comparison of the module (FAMILY) at
family-wise significance 0.01. On version 2 every case of test_02 fails (|z| 4.3 to 46).
Review mutations (each caught, |z| >= 9): the eta^2 of a chain crossing back over a
refracting interior boundary dropped ("clear over scattering, TIR"); the Jacobian of the
connection away from the exit taken with the exit slab's cosine ("clear air gap ...").
"""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.testing import sidak_z_limit

ALPHA = 0.01
WL = [550.0]
# `sample` without the entry interface's own delta reflection (the stack's other
# unscattered paths come back as walk exits and stay in).


def fresnel(cos_i, n_i, n_t):
    """Unpolarised dielectric reflectance (energy) and the transmitted cosine (0 at TIR)."""
    sin_t2 = (n_i / n_t) ** 2 * (1.0 - cos_i ** 2)
    if sin_t2 >= 1.0:
        return 1.0, 0.0
    cos_t = np.sqrt(1.0 - sin_t2)
    rs = (n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t)
    rp = (n_t * cos_i - n_i * cos_t) / (n_t * cos_i + n_i * cos_t)
    return 0.5 * (rs * rs + rp * rp), cos_t


def add(a, b):
    """Adding of two scalar layers (R front, T front, R back, T back), a above b."""
    d = 1.0 / (1.0 - a[2] * b[0])
    return (a[0] + a[1] * b[0] * a[3] * d, a[1] * b[1] * d, b[2] + b[3] * a[2] * b[1] * d, b[3] * a[3] * d)


def delta_parts(iors, slabs, cos_above, mirror=None):
    """Unscattered reflectance (the entry interface's own reflection included: sample()
    reports every path delta at each vertex as a delta lobe, like that reflection) and
    transmittance (energy) of smooth interfaces iors = [n_0 (above), n_1, ..., n_K (below)]
    with slabs (thickness, sigma_t) between, for light from above at cos_above. `mirror`:
    a base reflectance instead of the last interface (an opaque base)."""
    n = iors
    layers, cos = [], cos_above
    for k in range(len(slabs) + 1):
        if k == len(slabs) and mirror is not None:
            layers.append((mirror, 0.0, mirror, 0.0))
            break
        r, cos_t = fresnel(cos, n[k], n[k + 1])
        layers.append((r, 1.0 - r, r, 1.0 - r))
        if k < len(slabs):
            thickness, sigma_t = slabs[k]
            tau = np.exp(-sigma_t * thickness / cos_t) if cos_t > 0 else 0.0
            layers.append((0.0, tau, 0.0, tau))
            cos = cos_t
    total = layers[0]
    for layer in layers[1:]:
        total = add(total, layer)
    return total[0], total[1]


def split_albedos(model, wi, n, seed):
    """Reflection and transmission albedos of eval (wo uniform on each hemisphere; 4
    walks per eval) and of sample, each with its standard error."""
    rng = np.random.default_rng(seed)
    out = {}
    for side in (1.0, -1.0):  # wo on wi's side (reflection), then on the other one
        u1, u2 = rng.random(n), rng.random(n)
        r, phi = np.sqrt(1.0 - u1 ** 2), 2 * np.pi * u2
        wo = np.stack([r * np.cos(phi), r * np.sin(phi), side * np.sign(wi[2]) * u1], axis=1)
        est = model.estimate(np.tile(wi, (n, 1)), wo, wavelengths=WL, samples=4, seed=seed + 1)
        x = 2 * np.pi * est.value[:, 0]  # eval(wi, wo)|cos| over the uniform density 1 / 2 pi
        out["eval R" if side > 0 else "eval T"] = (x.mean(), x.std(ddof=1) / np.sqrt(n))
        assert est.nonfinite == 0
    s = model.sample(np.tile(wi, (2 * n, 1)), seed=seed + 2, wavelengths=WL, lobes=Lobe.ALL)
    w = s.weight[:, 0]
    for key, sel in (("sample R", s.wo[:, 2] * wi[2] > 0), ("sample T", s.wo[:, 2] * wi[2] < 0)):
        x = np.where(sel, w, 0.0)
        out[key] = (x.mean(), x.std(ddof=1) / np.sqrt(2 * n))
    return out


def scattering(tau, albedo=0.9, phase=None, thickness=1.0):
    sigma_t = tau / thickness
    return bl.Slab(thickness, sigma_a=(1 - albedo) * sigma_t, sigma_s=albedo * sigma_t, phase=phase)


FWD = {"type": "hg", "g": 0.6}
# A mirror within the indices' documented range (n, k <= 1e3): R >= 0.99999 at every angle,
# 1 - R far below the z-tests' resolution, so the closed form takes R = 1.
# name: (model factory, refractive indices top to bottom, slabs (thickness, sigma_t), mirror)
CASES = {
    # the oracle's repro: glass slab in air, smooth on both sides
    "glass iso tau.5": (lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [scattering(0.5)], bl.Dielectric(1.0, 1.5)),
                        [1.0, 1.5, 1.0], [(1.0, 0.5)], None),
    # forward scattering over a mirror: reflection only, bounces smooth top <-> mirror
    "mirror hg.6 tau1": (lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [scattering(1.0, 0.8, FWD)],
                                            bl.Conductor(eta=1.0, k=1000.0, ext_ior=1.5)),
                         [1.0, 1.5], [(1.0, 1.0)], 1.0),
    # three different indices: delta chains crossing a refracting interior boundary both
    # ways (eta^2 of each crossing, the Jacobian in the lower slab); water below
    "glass|1.3|water two slabs": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.3, 1.5)],
                           [scattering(0.4, 0.95, FWD), scattering(0.6, 0.7)], bl.Dielectric(1.33, 1.3)),
        [1.0, 1.5, 1.3, 1.33], [(1.0, 0.4), (1.0, 0.6)], None),
    # clear glass over a scattering slab, seen from water below: most light returned to
    # the slab comes back from total internal reflection at the top, through the 1.5 | 1.3
    # boundary twice (a wrong eta^2 on either crossing shifts R by 10 sigma or more)
    "clear over scattering, TIR": (
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.3, 1.5)],
                           [bl.Slab(1.0, sigma_a=0.05), scattering(0.2, 0.9)], bl.Dielectric(1.33, 1.3)),
        [1.0, 1.5, 1.3, 1.33], [(1.0, 0.05), (1.0, 0.2)], None),
    # a scattering slab below a refracting boundary, over a mirror: the connection away
    # from the exit dominates, and the slab's cosine differs from the exit slab's (a wrong
    # Jacobian |u_j.z| there shifts R by many sigma)
    "clear air gap over scattering 2.0, mirror": (
        lambda: bl.Layered([bl.Dielectric(1.0, 1.0), bl.Dielectric(2.0, 1.0)],
                           [bl.Slab(1.0, sigma_a=0.05), scattering(0.2, 0.9)],
                           bl.Conductor(eta=1.0, k=1000.0, ext_ior=2.0)),
        [1.0, 1.0, 2.0], [(1.0, 0.05), (1.0, 0.2)], 1.0),
}
# (case, cos theta of wi; negative: light from below)
QUERIES = [("glass iso tau.5", 0.5), ("glass iso tau.5", 0.12), ("glass iso tau.5", -0.7),
           ("mirror hg.6 tau1", 0.9), ("mirror hg.6 tau1", 0.15),
           ("glass|1.3|water two slabs", 0.8), ("glass|1.3|water two slabs", 0.2),
           ("glass|1.3|water two slabs", -0.6),
           ("clear over scattering, TIR", -0.6), ("clear over scattering, TIR", -0.3),
           ("clear air gap over scattering 2.0, mirror", 0.7),
           ("clear air gap over scattering 2.0, mirror", 0.25)]
ESTIMATORS = ("pfmc2", "pfmc")  # issue 32: both estimators (pfmc2 shares deterministic chains here)
# CI sample of test_02: 9 of the 24 query x estimator cases (every stack, light from above
# and from below where the stack has both, a grazing query, both estimators); the other 15
# carry the slow marker. Each set is its own family: the CI one with test_01's 2.
CI = {("glass iso tau.5", 0.5, "pfmc2"), ("glass iso tau.5", -0.7, "pfmc"),
      ("mirror hg.6 tau1", 0.9, "pfmc"), ("mirror hg.6 tau1", 0.15, "pfmc2"),
      ("glass|1.3|water two slabs", 0.2, "pfmc"), ("glass|1.3|water two slabs", -0.6, "pfmc2"),
      ("clear over scattering, TIR", -0.6, "pfmc2"), ("clear over scattering, TIR", -0.3, "pfmc"),
      ("clear air gap over scattering 2.0, mirror", 0.7, "pfmc2")}
PARAMS = [pytest.param(name, cos_theta, estimator, marks=() if (name, cos_theta, estimator) in CI else pytest.mark.slow)
          for name, cos_theta in QUERIES for estimator in ESTIMATORS]
FAMILY = 2 * len(CI) + 2
SLOW_FAMILY = 2 * (len(PARAMS) - len(CI))


def direction(cos_theta):
    c = abs(cos_theta)
    return np.array([np.sqrt(1 - c * c), 0.0, cos_theta])


def expected_delta(iors, slabs, cos_theta, mirror):
    """Delta reflection / transmission weights as `sample` reports them (radiance: a
    transmitted weight carries (n_entry / n_exit)^2)."""
    if cos_theta < 0:  # light from below: the mirrored stack
        iors, slabs = iors[::-1], slabs[::-1]
    r, t = delta_parts(iors, slabs, abs(cos_theta), mirror)
    return r, t * (iors[0] / iors[-1]) ** 2


def test_01_closed_form_delta_parts_match_the_sampler():
    """The test's own reference: a clear slab has only delta parts (eval 0), and the
    sampler's reflection / transmission albedos equal the adding formula."""
    m = bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.3, 1.5)],
                   [bl.Slab(1.0, sigma_a=0.3), bl.Slab(1.0, sigma_a=0.1)], bl.Dielectric(1.33, 1.3))
    for cos_theta in (0.7, -0.5):
        wi = direction(cos_theta)
        s = m.sample(np.tile(wi, (20_000, 1)), seed=3, wavelengths=WL, lobes=Lobe.ALL)
        reflected = s.wo[:, 2] * wi[2] > 0
        want = expected_delta([1.0, 1.5, 1.3, 1.33], [(1.0, 0.3), (1.0, 0.1)], cos_theta, None)
        for got, sel, ref in ((s.weight[:, 0], reflected, want[0]), (s.weight[:, 0], ~reflected, want[1])):
            x = np.where(sel, got, 0.0)
            if ref == 0:  # total internal reflection: nothing may come through
                assert not np.any(x), cos_theta
                continue
            z = (x.mean() - ref) / (x.std(ddof=1) / np.sqrt(len(x)))
            assert abs(z) < sidak_z_limit(ALPHA, FAMILY), (cos_theta, x.mean(), ref)


@pytest.mark.parametrize("name,cos_theta,estimator", PARAMS)
def test_02_eval_plus_delta_equals_sample(name, cos_theta, estimator):
    """Reflection and transmission separately: eval-albedo + delta part = sample-albedo.
    Mutation: Layered.estimate's value x 1.02 fails it (clear over scattering, TIR at -0.3,
    transmission: z 3.5 > 3.48; the 24-case family's higher limit would let it pass)."""
    factory, iors, slabs, mirror = CASES[name]
    m = bl.from_dict({**factory().to_dict(), "estimator": estimator})
    a = split_albedos(m, direction(cos_theta), 30_000, seed=11)
    r_delta, t_delta = expected_delta(iors, slabs, cos_theta, mirror)
    limit = sidak_z_limit(ALPHA, FAMILY if (name, cos_theta, estimator) in CI else SLOW_FAMILY)
    for side, delta in (("R", r_delta), ("T", t_delta)):
        (e, se), (s, ss) = a["eval " + side], a["sample " + side]
        if mirror is not None and side == "T":
            assert e == 0 and s == 0
            continue
        z = (e + delta - s) / np.hypot(se, ss)
        assert abs(z) < limit, (name, cos_theta, side, f"eval {e:.5f}+-{se:.1e} + delta {delta:.5f} "
                                                        f"vs sample {s:.5f}+-{ss:.1e}, z {z:.1f}")


def test_07_all_delta_stack_paths_are_labelled_delta_not_glossy():
    """Review finding: sample() labelled paths with no non-delta vertex (clear slab between
    smooth boundaries) glossy, although eval has no density for them; a renderer then
    MIS-weighted them against light sampling that sees eval = 0 and lost their energy.
    They are a delta lobe of the stack: excluded by a non-delta lobe mask, reported delta."""
    m = bl.Layered([bl.Dielectric(1.5, 1.0)], [bl.Slab(0.5, sigma_a=0.6)], bl.Dielectric(1.0, 1.5), samples=4)
    wi = np.tile([0.6, 0.0, 0.8], (4000, 1))
    glossy = m.sample(wi, seed=1, wavelengths=WL, lobes=Lobe.ALL & ~Lobe.DELTA)
    assert not np.any(np.asarray(glossy.lobe) != 0)  # nothing but delta paths in this stack
    every = m.sample(wi, seed=1, wavelengths=WL)
    lobe = np.asarray(every.lobe)
    assert np.all(lobe != 0) and np.all((lobe & int(Lobe.GLOSSY)) == 0)
    assert int(m.lobes) & int(Lobe.DELTA_TRANSMISSION) and int(m.lobes) & int(Lobe.DELTA_REFLECTION)
