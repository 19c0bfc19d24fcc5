"""PFMC (bsdflab.Layered) against the deterministic adding-doubling oracle for scattering
slabs: isotropic and Henyey-Greenstein (g = 0.6, -0.3) phase functions, optical depths
0.5-5, single-scattering albedos 0.5-0.99 (spectral sigma_a: one albedo per wavelength),
smooth 1.5 top, black / Lambertian / transmissive (glass-to-air) bases, grazing pairs
included, reflection and transmission from both sides.

Statistics. Each PFMC value v has a standard error s (eval_with_error, independent
walks per pair); the oracle r has a truncation bound e (its eval_with_error, ~1e-6
relative, far below s). A comparison passes when |v - r| <= z s + e. The family is
every (pair, wavelength) of every case in this module, FAST and SLOW separately:
family-wise false-alarm rate 0.01, Sidak-corrected per comparison
(bsdflab.testing.sidak_significance, two-sided normal quantile z, e.g. 4.6 for 1000
comparisons). Wavelengths share walks, so within a pair they are positively
correlated; Sidak's bound stays valid (conservative) for positively dependent tests.
A second check catches errors that are small per pair but systematic: per case the mean
of z over all (pair, wavelength) comparisons has a standard deviation <= 1 / sqrt(pairs)
(pairs are independent; wavelengths at worst fully correlated), so sqrt(pairs) times it
must lie within the same z (one more test per case in the family).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import bsdflab as bl
from bsdflab.oracles import AddingDoublingOracle
from bsdflab.spectra import Spectrum
from bsdflab.testing import random_unit_vectors, sidak_significance, spherical_directions

WL = [450.0, 550.0, 650.0]
FAMILY_SIGNIFICANCE = 0.01


def slab(tau, albedos, phase=None, thickness=1.0):
    """A slab of optical depth tau with one single-scattering albedo per wavelength of WL
    (grey sigma_s, spectral sigma_a)."""
    sigma_t = tau / thickness
    albedos = np.asarray(albedos, dtype=float)
    sigma_s = float(np.max(albedos)) * sigma_t
    sigma_a = sigma_s / albedos - sigma_s
    return bl.Slab(thickness, sigma_a=Spectrum.tabulated(WL, sigma_a), sigma_s=sigma_s, phase=phase)


ISO, FWD, BACK = None, {"type": "hg", "g": 0.6}, {"type": "hg", "g": -0.3}
TOP = bl.Dielectric(1.5, 1.0)
MATCHED = bl.Dielectric(1.5, 1.5)     # an index-matched smooth boundary (no optical effect)
AIR_BELOW = bl.Dielectric(1.0, 1.5)   # glass slab to air below: transmissive
OPEN_TOP, OPEN_BASE = bl.Dielectric(1.5, 1.5), bl.Dielectric(1.5, 1.5)  # no delta reflections

# name: (interfaces, slabs, base, sides) with sides "R" (reflection) and/or "T" (both ways)
FAST = {
    "iso tau1 w.5-.9 lambert": ([TOP], [slab(1.0, [0.5, 0.7, 0.9])], bl.Diffuse(0.5), "R"),
    "hg.6 tau5 w.9-.99 black": ([TOP], [slab(5.0, [0.9, 0.95, 0.99], FWD)], bl.Diffuse(0.0), "R"),
    "hg-.3 tau.5 w.5-.95 lambert": ([TOP], [slab(0.5, [0.5, 0.8, 0.95], BACK)], bl.Diffuse(0.8), "R"),
    "hg.6 tau2 w.7-.99 glass": ([TOP], [slab(2.0, [0.7, 0.9, 0.99], FWD)], AIR_BELOW, "RT"),
    "iso tau3 w.5-.99 matched both sides": ([OPEN_TOP], [slab(3.0, [0.5, 0.9, 0.99])], OPEN_BASE, "RT"),
}
SLOW = {
    f"{pname} tau{tau} {bname}": ([TOP], [slab(tau, [0.5, 0.9, 0.99], phase)], base, sides)
    for pname, phase in (("iso", ISO), ("hg.6", FWD), ("hg-.3", BACK))
    for tau in (0.5, 2.0, 5.0)
    for bname, base, sides in (("black", bl.Diffuse(0.0), "R"), ("lambert", bl.Diffuse(0.6), "R"),
                               ("glass", AIR_BELOW, "RT"))
}
SLOW["two slabs split by a matched boundary"] = (
    [TOP, MATCHED], [slab(1.0, [0.6, 0.9, 0.99], FWD), slab(2.0, [0.5, 0.8, 0.95], BACK)],
    bl.Diffuse(0.5), "R")


def directions(n, seed, sides):
    """n pairs: random, plus grazing ones (85 and 88 degrees) on both ends; for "T" the
    second half of the pairs has wo below and the last quarter wi below as well."""
    wi = random_unit_vectors(n, seed=seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=seed + 1, hemisphere="upper")
    graze = spherical_directions(np.radians([85.0, 88.0, 30.0, 88.0]), [0.0, 1.0, 2.0, 4.0])
    wi[:4], wo[4:8] = graze, graze
    if "T" in sides:
        h = n // 2
        wo[h:, 2] *= -1.0
        wi[h + h // 2:, 2] *= -1.0    # light from above, viewer below
        wo[h + h // 2:, 2] *= -1.0
    return wi, wo


def compare(case, n_pairs, samples, seed, family_size, estimator="pfmc"):
    interfaces, slabs, base, sides = case
    m = bl.Layered(interfaces, slabs, base, estimator=estimator)
    wi, wo = directions(n_pairs, seed, sides)
    value, err = m.eval_with_error(wi, wo, wavelengths=WL, samples=samples, seed=seed + 2)
    ref, ref_err = AddingDoublingOracle.from_layered(m).eval_with_error(wi, wo, wavelengths=WL)
    z_max = stats.norm.isf(sidak_significance(FAMILY_SIGNIFICANCE, family_size) / 2)
    assert np.all(err > 0) and np.all(ref > 0)
    excess = np.abs(value - ref) - ref_err
    z = excess / err
    worst = np.unravel_index(np.argmax(z), z.shape)
    assert np.max(z) <= z_max, (
        f"max z {np.max(z):.2f} > {z_max:.2f} at wi {wi[worst[0]]}, wo {wo[worst[0]]}, "
        f"{WL[worst[1]]} nm: PFMC {value[worst]:.6g} +- {err[worst]:.2g}, oracle {ref[worst]:.6g}")
    bias = np.mean((value - ref) / np.hypot(err, ref_err)) * np.sqrt(n_pairs)
    assert abs(bias) <= z_max, f"systematic offset: sqrt(pairs) mean z = {bias:.2f} > {z_max:.2f}"
    print(f"max z {np.max(z):.2f}, sqrt(pairs) mean z {bias:.2f}, limit {z_max:.2f}, "
          f"median PFMC rel. error {np.median(err / ref):.4f}, max oracle bound {np.max(ref_err / ref):.1e}")


# The smooth-glass-base cases were strict xfails until estimator version 3: PFMC eval
# missed scattering vertex -> delta reflection(s) -> exit through smooth boundaries
# ("iso tau0.5 glass" at 60 degrees, 550 nm: R 0.1387, T 0.1358 against the oracle's
# 0.1455, 0.1427). Version 3 counts them (delta-region connections, docs/estimators.md;
# tests/test_layered_delta_chains.py).


N_FAST, N_SLOW = 16, 32
ESTIMATORS = ("pfmc", "pfmc2")  # both layered estimators against the oracle (issue 21)
# test_01's CI sample: each FAST stack with one estimator, alternating (5 of 10); the other
# 5 carry the slow marker. Each set is its own family.
FAST_CI = {(name, ESTIMATORS[i % 2]) for i, name in enumerate(FAST)}
FAST_FAMILY = len(FAST_CI) * (N_FAST * len(WL) + 1)
FAST_SLOW_FAMILY = (len(ESTIMATORS) * len(FAST) - len(FAST_CI)) * (N_FAST * len(WL) + 1)
SLOW_FAMILY = len(SLOW) * (N_SLOW * len(WL) + 1)


@pytest.mark.parametrize("name, estimator", [
    pytest.param(n, e, marks=() if (n, e) in FAST_CI else pytest.mark.slow) for n in FAST for e in ESTIMATORS])
def test_01_pfmc_matches_adding_doubling(name, estimator):
    """Mutation: Layered.estimate's value x 1.02 fails it."""
    family = FAST_FAMILY if (name, estimator) in FAST_CI else FAST_SLOW_FAMILY
    compare(FAST[name], N_FAST, 8000, 11, family, estimator)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SLOW))
def test_02_long_study(name):
    compare(SLOW[name], N_SLOW, 20_000, 21, SLOW_FAMILY)
