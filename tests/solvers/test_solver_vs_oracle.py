"""The adding-doubling solver (bsdflab.solvers) against the independent numpy oracle
(bsdflab.oracles.AddingDoublingOracle) on smooth coats, and its own closed-form checks:
energy conservation of a lossless stack, reciprocity, the a-posteriori bound, bad input.

Tolerances. The oracle is accurate to ~1e-7 relative with its defaults (docs/oracles.md);
the solver's default truncations (16 nodes per panel, start depth 2^-12 with a
Richardson correction, orders to 1e-6) are measured in docs/solvers.md. The comparisons
are deterministic: a tolerance is a stated accuracy, not a statistic.
"""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.oracles import AddingDoublingOracle
from bsdflab.solvers import solve
from bsdflab.spectra import Spectrum
from bsdflab.testing import random_unit_vectors, spherical_directions

WL = [450.0, 550.0, 650.0]
RTOL_ORACLE = 2e-5


def slab(tau, albedos, phase=None, thickness=1.0):
    sigma_t = tau / thickness
    albedos = np.asarray(albedos, dtype=float)
    sigma_s = float(np.max(albedos)) * sigma_t
    sigma_a = sigma_s / albedos - sigma_s
    return bl.Slab(thickness, sigma_a=Spectrum.tabulated(WL, sigma_a), sigma_s=sigma_s, phase=phase)


FWD, BACK = {"type": "hg", "g": 0.6}, {"type": "hg", "g": -0.3}
TOP = bl.Dielectric(1.5, 1.0)
CASES = {
    "iso tau1 lambert": ([TOP], [slab(1.0, [0.5, 0.7, 0.9])], bl.Diffuse(0.5)),
    "hg.6 tau5 black": ([TOP], [slab(5.0, [0.9, 0.95, 0.99], FWD)], bl.Diffuse(0.0)),
    "hg-.3 tau.5 lambert": ([TOP], [slab(0.5, [0.5, 0.8, 0.95], BACK)], bl.Diffuse(0.8)),
    "two slabs, matched boundary": ([TOP, bl.Dielectric(1.5, 1.5)],
                                    [slab(1.0, [0.6, 0.9, 0.99], FWD), slab(2.0, [0.5, 0.8, 0.95], BACK)],
                                    bl.Diffuse(0.5)),
}


def pairs(n=24, seed=3):
    wi = random_unit_vectors(n, seed=seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=seed + 1, hemisphere="upper")
    graze = spherical_directions(np.radians([85.0, 88.0, 30.0, 89.0]), [0.0, 1.0, 2.0, 4.0])
    wi[:4], wo[4:8] = graze, graze
    return wi, wo


@pytest.mark.parametrize("name", list(CASES))
def test_01_matches_numpy_oracle_on_smooth_coats(name):
    model = bl.Layered(*CASES[name])
    wi, wo = pairs()
    ours = solve(model, WL).eval(wi, wo)
    ref = AddingDoublingOracle.from_layered(model).eval(wi, wo, wavelengths=WL)
    rel = np.max(np.abs(ours - ref) / ref)
    print(f"{name}: max relative difference {rel:.2e}")
    assert rel <= RTOL_ORACLE
