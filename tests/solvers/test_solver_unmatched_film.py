"""Review of the unmatched smooth interior interface (solve_snell): its film.

test_solver_unmatched_interior.py checks the interior film only against PFMC, where a
300 nm film of 1.38 reads max z 2.1 when left off (below the test's resolution), while
energy (a lossless film conserves), reciprocity (R and T of a lossless film are the same
from both sides) and continuity (no film there) cannot see it: the solver with the film
of an unmatched interior interface dropped passes that whole file. This test closes the
gap deterministically: as the contrast vanishes, the p-node solve of a strongly
reflecting film (n 2.3, 70 nm: R ~ 0.2 at 550 nm between 1.5 and 1.5) must meet the
index-matched solve of the same film-coated interface (the old code path, which solves
matched film-coated interior interfaces), as test_05 does without a film.
"""

from __future__ import annotations

import numpy as np

import bsdflab as bl
from bsdflab.solvers import solve
from bsdflab.testing import random_unit_vectors, spherical_directions

WL = [450.0, 550.0, 650.0]
HG = bl.Slab(2.0, sigma_a=0.1, sigma_s=0.5, phase={"type": "hg", "g": 0.6})
ISO = bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0)
FILM = [{"material": 2.3, "thickness_nm": 70.0}]


def _pairs():
    kinds = (("upper", "upper"), ("lower", "upper"), ("lower", "lower"), ("upper", "lower"))
    graze = spherical_directions(np.radians([88.0, 86.0, 87.0, 88.0]), [0.5, 1.0, 2.0, 3.0])
    wis, wos = [], []
    for k, (hi, ho) in enumerate(kinds):
        wi = random_unit_vectors(3, seed=17 + 2 * k, hemisphere=hi)
        wo = random_unit_vectors(3, seed=18 + 2 * k, hemisphere=ho)
        wo[0] = graze[k] * np.array([1.0, 1.0, 1.0 if ho == "upper" else -1.0])
        wis.append(wi)
        wos.append(wo)
    return np.concatenate(wis), np.concatenate(wos)


def test_interior_film_continuous_with_the_matched_solve():
    def model(n):
        return bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(n, 1.5, film=FILM)], [HG, ISO], bl.Dielectric(1.0, n))

    wi, wo = _pairs()
    matched = solve(model(1.5), WL).eval(wi, wo)
    bare = solve(
        bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.5, 1.5)], [HG, ISO], bl.Dielectric(1.0, 1.5)), WL
    ).eval(wi, wo)
    film_effect = np.max(np.abs(bare - matched) / matched)
    up, down = (solve(model(1.5 * (1 + e)), WL).eval(wi, wo) for e in (1e-3, -1e-3))
    rel = np.max(np.abs(0.5 * (up + down) - matched) / matched)
    print(f"film effect {film_effect:.1e}; symmetric mean vs matched {rel:.1e}")
    assert film_effect > 1e-2  # the film matters far beyond the tolerance
    assert rel <= 5e-5, rel


def test_bound_covers_the_error_at_vanishing_contrast():
    """eval_with_error's bound (the change to the half-node solve) must cover the error.
    At an interior contrast of 1e-7 the exact answer is the index-matched one to ~1e-6
    relative (test_05: the physics changes by 2e-3 per 1e-3 of contrast), and the matched
    solve (old path) is converged at 16 nodes; so |v - matched| <= e + 1e-6 |matched|.
    Measured at 16 nodes, 550 nm: error 5e-4 relative, bound 1e-5 (error / bound ~ 50 at
    every pair): the grazing Fresnel feature of width ~sqrt(contrast) is unresolved by both
    the solve and its coarser twin, which therefore agree."""

    def model(n):
        return bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(n, 1.5)], [HG, ISO], bl.Dielectric(1.0, n))

    wi, wo = _pairs()
    matched = solve(model(1.5), [550.0]).eval(wi, wo)
    v, e = solve(model(1.5 * (1 + 1e-7)), [550.0]).eval_with_error(wi, wo)
    excess = np.abs(v - matched) - e - 1e-6 * np.abs(matched)
    ratio = np.abs(v - matched) / e
    print(f"max rel error {np.max(np.abs(v - matched) / matched):.1e}, max error / bound {np.max(ratio):.1f}")
    assert np.all(excess <= 0), np.max(ratio)
