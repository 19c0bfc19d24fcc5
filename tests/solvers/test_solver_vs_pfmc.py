"""Cross-validation: the adding-doubling solver against PFMC (bsdflab.Layered) on the
snake presets and rough coats (GGX and Beckmann, alpha 0.05-0.5, films, a scattering
slab over a Lambertian base), grazing pairs included, three spectral channels.

Both sides compare the light that entered the stack (``scattered_only``: the top's own
reflection is the same exact evaluation in both and would only dilute the test).

Statistics. Each PFMC value v has a standard error s (independent walks per pair); the
solver's value r has its a-posteriori bound e (Solution.eval_with_error, deterministic).
A comparison passes when |v - r| <= z s + e. The family is every (pair, wavelength) of
every case in this module plus one mean-z test per case: family-wise false-alarm rate
alpha = 0.01, Sidak-corrected per comparison (bsdflab.testing.sidak_significance; the
wavelengths of one pair share walks, positively dependent tests for which Sidak stays
conservative). The mean-z test catches small systematic offsets: per case sqrt(pairs)
times the mean z must lie within the same z. Power: a solver that drops the slab's
scattering (sigma_s -> 0 in the solved model) fails the xenopeltis case (checked by hand,
docs/solvers.md).

CI runs a sample (CI below: 5 of the 12 case-estimator pairs, each distribution, the
roughness extremes, the preset, its stack and a film, both estimators); the rest carry the
slow marker. Each set is its own family at alpha = 0.01 (the normal suite's over the CI
cases it runs, ``-m slow``'s over the others).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import bsdflab as bl
from bsdflab.presets import preset
from bsdflab.solvers import solve
from bsdflab.testing import random_unit_vectors, sidak_significance, spherical_directions

WL = [450.0, 550.0, 650.0]
FAMILY_SIGNIFICANCE = 0.01
N_PAIRS, SAMPLES = 10, 20000

SLAB = bl.Slab(2.0, sigma_a=0.1, sigma_s=0.5, phase={"type": "hg", "g": 0.6})
FILM = [{"material": 1.83, "thickness_nm": 400.0}]


def coat(alpha, distribution="ggx", film=None):
    top = bl.RoughDielectric(alpha, int_ior=1.5, ext_ior=1.0, film=film, distribution=distribution)
    return bl.Layered([top], [SLAB], bl.Diffuse(0.5))


CASES = {
    "xenopeltis": lambda: preset("xenopeltis"),
    "xenopeltis-stack": lambda: preset("xenopeltis-stack"),
    "xenopeltis-thin-film": lambda: preset("xenopeltis-thin-film"),
    "ggx 0.05 film": lambda: coat(0.05, film=FILM),
    "ggx 0.2": lambda: coat(0.2),
    "beckmann 0.5": lambda: coat(0.5, "beckmann"),
}
ESTIMATORS = ("pfmc", "pfmc2")  # both layered estimators (issue 21)
# CI sample: every case kind once or so, each estimator, both distributions, the
# roughness extremes (0.05 with a film, 0.5), the preset and its multi-slab stack
CI = {("xenopeltis", "pfmc"), ("xenopeltis-stack", "pfmc2"), ("ggx 0.05 film", "pfmc2"),
      ("ggx 0.2", "pfmc"), ("beckmann 0.5", "pfmc")}
PARAMS = [pytest.param(n, e, marks=() if (n, e) in CI else pytest.mark.slow) for n in CASES for e in ESTIMATORS]
CI_FAMILY = len(CI) * (N_PAIRS * len(WL) + 1)
SLOW_FAMILY = (len(PARAMS) - len(CI)) * (N_PAIRS * len(WL) + 1)


def directions(n, seed):
    wi = random_unit_vectors(n, seed=seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=seed + 1, hemisphere="upper")
    graze = spherical_directions(np.radians([85.0, 88.0, 30.0, 88.0]), [0.0, 1.0, 2.0, 4.0])
    wi[:4], wo[4:8] = graze, graze
    return wi, wo


@pytest.mark.parametrize("name, estimator", PARAMS)
def test_01_solver_matches_pfmc(name, estimator):
    """Mutation: the solver's value x 1.02 fails it (the xenopeltis case)."""
    m = CASES[name]()
    model = bl.Layered(list(m.interfaces), list(m.slabs), m.base, estimator=estimator)
    wi, wo = directions(N_PAIRS, 21)
    est = model.estimate(wi, wo, wavelengths=WL, samples=SAMPLES, seed=5, scattered_only=True)
    ref, ref_err = solve(model, WL).eval_with_error(wi, wo, scattered_only=True)
    family = CI_FAMILY if (name, estimator) in CI else SLOW_FAMILY
    z_max = stats.norm.isf(sidak_significance(FAMILY_SIGNIFICANCE, family) / 2)
    z = (np.abs(est.value - ref) - ref_err) / est.stderr
    signed = (est.value - ref) / np.hypot(est.stderr, ref_err)
    worst = np.unravel_index(np.argmax(z), z.shape)
    print(f"{name}: max z {np.max(z):.2f}, sqrt(pairs) mean z "
          f"{np.mean(signed) * np.sqrt(N_PAIRS):.2f}, limit {z_max:.2f}, median PFMC rel. error "
          f"{np.median(est.stderr / ref):.4f}, max solver bound {np.max(ref_err / ref):.1e}")
    assert np.max(z) <= z_max, (
        f"max z {np.max(z):.2f} > {z_max:.2f} at wi {wi[worst[0]]}, wo {wo[worst[0]]}, "
        f"{WL[worst[1]]} nm: PFMC {est.value[worst]:.6g} +- {est.stderr[worst]:.2g}, solver {ref[worst]:.6g}")
    assert abs(np.mean(signed) * np.sqrt(N_PAIRS)) <= z_max
