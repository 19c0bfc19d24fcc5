"""The fit recovers a target's parameters when the target's own model is the truth.

Synthetic truth: each target's comparison model (MaterialX's Belcour-Barla, glTF's
iridescence, Cycles' thin film) evaluated at known (thickness, film index, base index) over
the fit's angle x thickness-scale grid. The fit starts from the snake's film (400 nm,
1.83, 1.5515), 7-9 % away, and must land on the truth: Delta E00 ~ 0 everywhere, the
parameters within 0.5 nm and 0.005 (the map's sensitivity to them is far larger:
1 nm moves the colour by ~1 Delta E00 at 400 nm). Deterministic (no noise).
"""
from __future__ import annotations

import pytest

from bsdflab.export.fit import fit, target_rgb
from bsdflab.export.material import ExportMaterial
from bsdflab.export.targets import TARGETS

TRUTH = (430.0, 1.78, 1.52)
START = ExportMaterial(ext_ior=1.0, int_ior=1.5515, film_ior=1.83, film_thickness_nm=400.0, alpha=0.08,
                       body_rgb=(0.05, 0.035, 0.025))


@pytest.mark.parametrize("fmt", ["openpbr", "gltf", "blender"])
def test_fit_recovers_the_targets_own_parameters(fmt):
    t = TARGETS[fmt]
    truth = target_rgb(t, *TRUTH)
    f = fit(START, t, reference=truth)
    assert f.delta_e.max() < 0.05, f.summary()
    assert abs(f.thickness_nm - TRUTH[0]) < 0.5
    assert abs(f.film_ior - TRUTH[1]) < 0.005
    assert abs(f.base_ior - TRUTH[2]) < 0.005


def test_fit_against_the_exact_film_is_better_than_copying():
    """Against the exact film the fit must not be worse than copying the material's own
    parameters (the starting point is on the fit's grid)."""
    t = TARGETS["openpbr"]
    f = fit(START, t)
    from bsdflab.reference.approximations.study import delta_e00

    copied = delta_e00(target_rgb(t, 400.0, 1.83, 1.5515), f.exact_rgb)
    assert f.delta_e.mean() <= copied.mean() + 1e-9
    s = f.summary()
    assert 0 <= s["share_above_2"] <= s["share_above_1"] <= 1
