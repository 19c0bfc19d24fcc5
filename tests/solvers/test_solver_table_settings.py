"""The adding-doubling solver at the truncations tables use (bsdflab.tables.deterministic.
table_settings: looser orders, a thicker start, what lies below a rough top solved at every
4th wavelength and interpolated, coarser fine sub-panels), and what it does not solve.

Tolerances are deterministic: the a-posteriori bound of ``eval_with_error`` must exceed the
actual error against a reference solve whose every truncation is finer (20 nodes, 256
azimuth samples, every wavelength solved, the default orders, start and fine step).
"""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.presets import preset
from bsdflab.solvers import solve
from bsdflab.tables.deterministic import table_settings
from bsdflab.testing import random_unit_vectors, spherical_directions

WL33 = np.linspace(380.0, 780.0, 33)  # >= 32 wavelengths: the spectral stride applies


def pairs(n=12, seed=5):
    wi = random_unit_vectors(n, seed=seed, hemisphere="upper")
    wo = random_unit_vectors(n, seed=seed + 1, hemisphere="upper")
    graze = spherical_directions(np.radians([85.0, 88.0, 60.0]), [0.0, 1.0, 3.0])
    wi[:3], wo[3:6] = graze, graze
    return wi, wo


def test_01_table_settings_bound_covers_the_error():
    """The snake at table settings (1 %): every channel's error against the reference is
    below the stated bound, and the bound itself is below 2 % relative where the value
    is above 1 % of the largest (what tables report). The reference at 20 nodes (8.7
    CPU-s against 11.5 at 24) lies within 1.5 % of the bound of the 24-node one (error /
    bound 0.628 both). Mutation: eval_with_error's bound scaled by 0.5 fails it."""
    model = preset("xenopeltis")
    wi, wo = pairs()
    settings = table_settings(0.01, len(WL33))
    assert settings["spectral_stride"] == 4
    value, bound = solve(model, WL33, film_lookup=True, **settings).eval_with_error(wi, wo, scattered_only=True)
    ref = solve(model, WL33, nodes=20, azimuth_samples=256, film_lookup=True).eval(wi, wo, scattered_only=True)
    err = np.abs(value - ref)
    ratio = err / np.maximum(bound, 1e-300)
    significant = ref > 0.01 * ref.max()
    print(f"max error {np.max(err[significant] / ref[significant]):.2e}, max error / bound {ratio.max():.3f}, "
          f"max bound {np.max(bound[significant] / ref[significant]):.2e}")
    assert np.all(err <= bound + 1e-12 * np.abs(ref))
    assert np.max(bound[significant] / ref[significant]) < 0.02


def test_02_spectral_stride_interpolates_smooth_stacks():
    """What lies below the rough top solved at every 4th wavelength (cubic in wavelength
    between) agrees with solving every wavelength to 1e-3 relative on the snake (a
    melanin power law and a smooth base spectrum below the film)."""
    model = preset("xenopeltis")
    wi, wo = pairs(8, seed=11)
    every = solve(model, WL33, film_lookup=True, fine_step=0.5).eval(wi, wo, scattered_only=True)
    strided = solve(model, WL33, film_lookup=True, fine_step=0.5, spectral_stride=4).eval(wi, wo,
                                                                                          scattered_only=True)
    rel = np.abs(strided - every) / np.abs(every)
    print(f"max relative difference {rel.max():.2e}")
    assert rel.max() < 1e-3


def test_03_transmissive_stack_raises_for_unsolved_pairs():
    """The one transmissive stack whose pairs below are not solved, a rough base under a
    smooth interior interface between unequal indices, raises ValueError ``[rough-exit]``
    for them (instead of returning 0) and still solves reflection from above; a rough top
    over a smooth base solves every pair; an opaque stack returns its value, 0, below
    (test_solver_refusals.py covers every top on every base)."""
    slab = bl.Slab(1.0, sigma_a=0.1, sigma_s=0.5, phase={"type": "hg", "g": 0.6})
    up = spherical_directions(np.radians([30.0]), [0.0])
    down = -spherical_directions(np.radians([40.0]), [1.0])
    gap = bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.3, 1.5)], [slab, slab],
                     bl.RoughDielectric(0.3, 1.0, 1.3))
    sol = solve(gap, [550.0], nodes=8)
    assert not sol.every_pair
    assert sol.eval(up, up)[0, 0] > 0
    for wi, wo in ((down, up), (up, down), (down, down)):
        for call in (sol.eval, sol.eval_with_error):
            with pytest.raises(ValueError, match=r"\[rough-exit\].*rough base under a smooth interior interface"):
                call(wi, wo)
    rough_top = solve(bl.Layered([bl.RoughDielectric(0.2, 1.5, 1.0)], [slab], bl.Dielectric(1.0, 1.5)),
                      [550.0], nodes=8)
    assert rough_top.every_pair
    for wi, wo in ((down, up), (up, down), (down, down)):
        v = rough_top.eval(wi, wo)
        assert np.isfinite(v[0, 0]) and v[0, 0] > 0
    opaque = solve(preset("xenopeltis"), [550.0])
    assert opaque.eval(down, up)[0, 0] == 0.0


def test_04_bad_settings():
    model = preset("xenopeltis")
    with pytest.raises(ValueError, match=r"spectral_stride must be an integer in \[1, 64\]"):
        solve(model, spectral_stride=0)
    with pytest.raises(ValueError, match=r"fine_step must be"):
        solve(model, fine_step=5.0)
    with pytest.raises(ValueError, match=r"azimuth_samples must be an integer in \[8, 16384\]"):
        solve(model, azimuth_samples=4)
