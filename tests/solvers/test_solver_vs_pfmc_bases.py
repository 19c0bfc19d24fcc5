"""The adding-doubling solver against PFMC on the configurations it solves that the other
z-tests do not cover (tests/solvers/test_solver_refusals.py enumerates them): smooth
conductor bases with a film, rough conductor bases, spectral measured bases, a rough
dielectric base (reflection from above), a Beckmann multiscatter top, a film-coated
index-matched interior interface and a rough interior interface over an opaque base;
10 pairs each with grazing ones (86, 88 deg on either side), 450/550/650 nm, the full eval
(no delta lobes) on both sides.

Statistics as tests/solvers/test_solver_vs_pfmc.py: |v - r| <= z s + e (s PFMC's standard
error, e the solver's bound); family = every (pair, wavelength) of every case plus one
sqrt(pairs) x mean-z test per case, alpha = 0.01 family-wise, Sidak. Power: the solver
run on a mutated model (the conductor base's film removed) fails (checked once by hand,
docs/solvers.md "Solved and refused").
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import bsdflab as bl
from bsdflab.measured import export_model
from bsdflab.solvers import solve
from bsdflab.testing import random_unit_vectors, sidak_significance, spherical_directions

WL = [450.0, 550.0, 650.0]
FAMILY_SIGNIFICANCE = 0.01
N_PAIRS, SAMPLES = 10, 20000
FILM = [{"material": 1.83, "thickness_nm": 300.0}]
HG = bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0, phase={"type": "hg", "g": 0.5})
ISO = bl.Slab(1.0, sigma_a=0.3, sigma_s=0.8)


def _measured(folder):
    path = folder / "cu_spec.bsdf"
    export_model(
        bl.RoughConductor(alpha=0.3, material="Cu"), path, wavelengths=WL, n_theta_i=6, resolution=16, error_points=200
    )
    return bl.Measured(path)


CASES = {
    "smooth / HG / conductor Au + film": lambda f: bl.Layered(
        [bl.Dielectric(1.5, 1.0)], [HG], bl.Conductor(material="Au", ext_ior=1.5, film=FILM)
    ),
    "smooth / HG / rough conductor Cu 0.3": lambda f: bl.Layered(
        [bl.Dielectric(1.5, 1.0)], [HG], bl.RoughConductor(0.3, material="Cu", ext_ior=1.5)
    ),
    "ggx 0.2 / iso / spectral measured": lambda f: bl.Layered([bl.RoughDielectric(0.2, 1.5, 1.0)], [ISO], _measured(f)),
    "smooth / HG / rough dielectric 0.3 to water": lambda f: bl.Layered(
        [bl.Dielectric(1.5, 1.0)], [HG], bl.RoughDielectric(0.3, 1.33, 1.5)
    ),
    "beckmann 0.4 multiscatter / HG / Lambertian": lambda f: bl.Layered(
        [bl.RoughDielectric(0.4, 1.5, 1.0, distribution="beckmann", multiscatter=True)], [HG], bl.Diffuse(0.5)
    ),
    "smooth / HG / matched film / iso / Lambertian": lambda f: bl.Layered(
        [bl.Dielectric(1.5, 1.0), bl.Dielectric(1.5, 1.5, film=FILM)], [HG, ISO], bl.Diffuse(0.4)
    ),
    "smooth / HG / ggx 0.5 1.5-2.0 / iso / Lambertian": lambda f: bl.Layered(
        [bl.Dielectric(1.5, 1.0), bl.RoughDielectric(0.5, 2.0, 1.5)], [HG, ISO], bl.Diffuse(0.4)
    ),
}
FAMILY = len(CASES) * (N_PAIRS * len(WL) + 1)


def directions(n, seed):
    wi = random_unit_vectors(n, seed=seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=seed + 1, hemisphere="upper")
    graze = spherical_directions(np.radians([86.0, 88.0]), [0.0, 2.0])
    wi[:2], wo[2:4] = graze, graze
    return wi, wo


def z_scores(model, solved_model):
    wi, wo = directions(N_PAIRS, 31)
    est = model.estimate(wi, wo, wavelengths=WL, samples=SAMPLES, seed=7)
    ref, ref_err = solve(solved_model, WL, nodes=24).eval_with_error(wi, wo)
    z = (np.abs(est.value - ref) - ref_err) / est.stderr
    signed = (est.value - ref) / np.hypot(est.stderr, ref_err)
    return z, float(np.mean(signed) * np.sqrt(N_PAIRS)), est, ref, ref_err


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("name", list(CASES))
def test_01_solver_matches_pfmc(name, tmp_path):
    model = CASES[name](tmp_path)
    z, mean_z, est, ref, ref_err = z_scores(model, model)
    z_max = stats.norm.isf(sidak_significance(FAMILY_SIGNIFICANCE, FAMILY) / 2)
    print(
        f"{name}: max z {np.max(z):.2f}, sqrt(pairs) mean z {mean_z:.2f}, limit {z_max:.2f}, median PFMC "
        f"rel. error {np.median(est.stderr / ref):.4f}, max solver bound {np.max(ref_err / ref):.1e}"
    )
    assert np.max(z) <= z_max
    assert abs(mean_z) <= z_max
