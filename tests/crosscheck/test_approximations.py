"""The comparison models of reference/approximations (the industry's thin-film shortcuts)
against their specifications' stated behaviour. The registry check
films/approximations/specifications holds the main statements (film index = outer index,
series = exact, Gaussian fit at normal incidence); these are the remaining unit facts."""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.reference.approximations import (
    belcour_barla_rgb,
    double_phase_reflectance,
    double_phase_rgb,
    gltf_iridescence_rgb,
    xyz_sensitivity_exact,
    xyz_sensitivity_gaussian,
)
from bsdflab.reference.approximations.belcour_barla import XYZ_TO_CIE_RGB
from bsdflab.reference.approximations.standards import SNAKE_FILM, STANDARDS, can_represent
from bsdflab.reference.approximations.study import delta_e00, exact_rgb, film_study


def test_sensitivities_are_normalised_to_white():
    # the paper's constant 1.0685e-7 makes S(0, 0) = 1 in X, Y and Z to ~1e-3 (its 5 digits)
    assert np.allclose(xyz_sensitivity_gaussian(0.0, 0.0), 1.0, atol=2e-3, rtol=0)
    assert np.allclose(xyz_sensitivity_exact(0.0, 0.0), 1.0, atol=1e-12, rtol=0)   # D65 -> sRGB white
    assert np.allclose(XYZ_TO_CIE_RGB @ np.ones(3), 1.0, atol=1e-6, rtol=0)       # E white stays white
    # both decay for long path differences (the eye averages the fringes away)
    assert np.all(np.abs(xyz_sensitivity_gaussian(20000.0, 0.0)) < 1e-3)


def test_double_phase_formula_reproduces_the_counter_example():
    assert round(float(double_phase_reflectance(1.0, 1.56, 1.83, 400.0, 475.0, np.cos(0.4))), 4) == 0.0854
    # with the film index outside both neighbours the extra pi is not a double count only by
    # accident of the formula: it still differs from the exact value
    rgb = double_phase_rgb(1.0, 1.83, 1.5515, 400.0, 1.0)
    assert rgb.shape == (3,)


def test_no_film_reduces_every_model_to_the_bare_interface_at_normal_incidence():
    # d = 0: Belcour-Barla and the double-phase formula give the bare Fresnel reflectance ((n1 - n3)/(n1 + n3))^2
    bare = ((1.0 - 1.5) / (1.0 + 1.5)) ** 2
    exact_series = belcour_barla_rgb(1.0, 1.8, 1.5, 0.0, 1.0, sensitivity="exact", terms=60)
    assert np.allclose(exact_series, bare, atol=1e-12, rtol=0)
    assert np.allclose(double_phase_rgb(1.0, 1.5, 1.5, 123.0, 1.0), bare, atol=1e-12, rtol=0)
    # glTF: Schlick's F0 of the base through the film; the 1e-5 clamp leaves < 1e-2
    assert np.allclose(gltf_iridescence_rgb(1.0, 1.8, 1.5, 0.0, 1.0), bare, atol=1e-2, rtol=0)


def test_total_internal_reflection_and_bad_terms():
    assert np.allclose(belcour_barla_rgb(1.8, 1.2, 1.5, 300.0, 0.2), 1.0, atol=1e-6, rtol=0)
    assert np.all(gltf_iridescence_rgb(1.8, 1.2, 1.5, 300.0, 0.2) == 1.0)
    with pytest.raises(ValueError, match="terms"):
        belcour_barla_rgb(1.0, 1.8, 1.5, 300.0, 1.0, terms=0)
    with pytest.raises(ValueError, match="sensitivity"):
        belcour_barla_rgb(1.0, 1.8, 1.5, 300.0, 1.0, sensitivity="fast")


def test_study_is_zero_for_the_exact_model_and_large_for_the_seed():
    s = film_study("t", 1.0, 1.83, 1.55, [0.0, 45.0], [100.0, 400.0, 900.0],
                   models={"exact": exact_rgb, "double-phase": double_phase_rgb})
    assert np.max(s.delta_e["exact"]) < 1e-9
    assert s.fraction_over("double-phase") > 0.5 and s.summary()["double-phase"]["max_delta_e00"] > 5
    assert delta_e00([0.2, 0.2, 0.2], [0.2, 0.2, 0.2]) == 0.0


def test_every_standard_can_hold_the_snake_film():
    assert all(can_represent(s) for s in STANDARDS.values())
    narrow = dict(next(iter(STANDARDS.values())), thickness_nm=(100.0, 400.0))
    assert not can_represent(narrow, SNAKE_FILM)
