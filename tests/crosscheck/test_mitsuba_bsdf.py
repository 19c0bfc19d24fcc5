"""bsdflab's BSDFs against Mitsuba 3, query by query (bsdflab.reference.mitsuba_bsdf).

Every standard material is compared on 1000 random pairs (wi from both hemispheres,
grazing ones included; near-critical ones for dielectrics): eval, pdf, and the sample
drawn with identical uniforms (direction, weight, pdf, lobe type, eta). Well-conditioned
pairs must agree to 1e-5 relative; pairs float32 cannot resolve (near the critical angle,
grazing, rare lobes) must stay within their own float32 bound, and are counted, not
dropped. The coloured diffuse is checked both in sRGB, with the target widened by the
documented spectral round trip (bsdflab lifts RGB to a spectrum; Mitsuba's RGB variant
does not), and per wavelength, where no such model difference exists.
"""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.bsdfs import Conductor, Dielectric, Diffuse
from bsdflab.lobes import Lobe
from bsdflab.reference import mitsuba_bsdf as mb
from bsdflab.reference.comparison import TARGET, assert_agrees
from bsdflab.reference.mitsuba_env import VARIANTS, mitsuba, variant
from bsdflab.reference.query_sets import draw_queries

pytestmark = pytest.mark.mitsuba

CASES = mb.standard_cases()
SRGB_ROUND_TRIP_LIMIT = 3e-4  # documented bound on bsdflab's RGB -> spectrum -> sRGB error


_assert_agrees = assert_agrees  # passed, within target / bounds, no pair dropped


@pytest.mark.parametrize("name, bsdf, wavelength", CASES, ids=[c[0] for c in CASES])
def test_01_standard_materials_agree_with_mitsuba(name, bsdf, wavelength):
    c = mb.compare_bsdf(bsdf, n_pairs=1000, seed=0, wavelength=wavelength)
    _assert_agrees(c)
    if wavelength is not None:
        assert c.target == TARGET
    # samples exist from both sides exactly when the model reflects or refracts there
    one_sided = not bsdf.to_dict().get("two_sided") and not isinstance(bsdf, Dielectric)
    assert c.n_sampled == (500 if one_sided else 1000)


def test_02_required_materials_are_in_the_standard_set():
    names = {c[0] for c in CASES}
    for required in ("diffuse-grey", "diffuse-rgb-srgb", "diffuse-two-sided",
                     "conductor-Au-450nm", "conductor-Au-550nm", "conductor-Au-650nm",
                     "conductor-Ag", "conductor-Cu", "conductor-Al", "conductor-mirror",
                     "conductor-custom", "dielectric-glass", "dielectric-int-lt-ext",
                     "dielectric-diamond"):
        assert required in names


def test_03_coloured_diffuse_srgb_tolerance_is_the_spectral_round_trip():
    c = mb.compare_bsdf(Diffuse([0.8, 0.3, 0.1]), n_pairs=1000, wavelength=None)
    round_trip = c.target - TARGET
    assert 0 < round_trip <= SRGB_ROUND_TRIP_LIMIT
    assert "round trip" in c.model_difference
    # the sRGB difference is that round trip (plus float32), not more
    assert c.eval_error <= round_trip + TARGET and c.weight_error <= round_trip + TARGET
    # per wavelength there is no model difference: 1e-5 holds
    c550 = mb.compare_bsdf(Diffuse([0.8, 0.3, 0.1]), n_pairs=1000, wavelength=550.0)
    assert c550.target == TARGET and c550.passed, c550.report()


def test_04_dielectric_from_both_sides_incl_total_internal_reflection_and_critical_angle():
    c = mb.compare_bsdf(Dielectric(1.5, 1.0), n_pairs=1000, seed=3)
    _assert_agrees(c)
    near = [g for g in c.ill_conditioned if g.reason.startswith("near the critical angle")]
    assert near and near[0].count >= 10  # the deliberately near-critical pairs are reported
    assert "near the critical angle" in c.report()


@pytest.mark.parametrize("seed", [1, 2])
def test_05_other_seeds_and_more_pairs(seed):
    for bsdf in (Dielectric(2.419, 1.000277), Dielectric(1.0, 1.33), Diffuse(0.7, two_sided=True),
                 Conductor("Au", two_sided=True)):
        _assert_agrees(mb.compare_bsdf(bsdf, n_pairs=4000, seed=seed, wavelength=600.0))


def test_06_to_mitsuba_dicts():
    assert mb.to_mitsuba(Diffuse(0.25), 550) == {"type": "diffuse", "reflectance": 0.25}
    assert mb.to_mitsuba(Diffuse([0.8, 0.3, 0.1])) == {
        "type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.3, 0.1]}}
    assert mb.to_mitsuba(Diffuse(0.5, two_sided=True), 550) == {
        "type": "twosided", "bsdf": {"type": "diffuse", "reflectance": 0.5}}
    assert mb.to_mitsuba(Conductor(), 550) == {"type": "conductor"}
    assert mb.to_mitsuba(Dielectric(2.419, 1.0).to_dict()) == {
        "type": "dielectric", "int_ior": 2.419, "ext_ior": 1.0}
    # Mitsuba 3's conductor has no exterior index: bsdflab's absolute index is divided by it
    p = mb.to_mitsuba(Conductor(eta=1.7, k=2.3, ext_ior=1.33), 550)
    assert p["eta"] == pytest.approx(1.7 / 1.33, rel=1e-15)
    assert p["k"] == pytest.approx(2.3 / 1.33, rel=1e-15)
    au = Conductor("Au")
    p = mb.to_mitsuba(au, 650)
    assert p["eta"] == pytest.approx(au.eta.at([650])[0] / au.ext_ior, rel=1e-15)
    mitsuba().load_dict(p)  # Mitsuba accepts it


def test_07_to_mitsuba_rejects_what_it_cannot_convert():
    with pytest.raises(ValueError, match="unknown BSDF type"):
        mb.to_mitsuba({"type": "nope"}, 550)
    with pytest.raises(ValueError, match="tabulated"):
        mb.to_mitsuba(Conductor("Cu"))  # a measured spectrum needs a wavelength
    with pytest.raises(ValueError, match="tabulated"):
        mb.to_mitsuba(Diffuse({"type": "tabulated", "wavelengths": [400, 700], "values": [0.2, 0.6]}))
    for bad in (0.0, -5, float("nan"), "red"):
        with pytest.raises(ValueError, match="wavelength"):
            mb.to_mitsuba(Diffuse(0.5), bad)
    with pytest.raises(ValueError, match="BSDF"):
        mb.to_mitsuba(42, 550)
    coated = {**Conductor("Au").to_dict(), "film": [{"material": 1.5, "thickness_nm": 400}]}
    with pytest.raises(ValueError, match="thin-film"):
        mb.to_mitsuba(coated, 550)
    # rough interfaces convert (test_mitsuba_rough.py), but Mitsuba 3 has no coated one
    rough = {"type": "roughdielectric", "film": [{"material": 1.5, "thickness_nm": 400}]}
    with pytest.raises(ValueError, match="thin-film"):
        mb.to_mitsuba(rough, 550)
    with pytest.raises(ValueError, match="n_pairs"):
        mb.compare_bsdf(Diffuse(0.5), n_pairs=0)


def test_08_a_model_without_a_counterpart_is_a_value_error(monkeypatch):
    d = {"type": "future_model"}  # a bsdflab model Mitsuba has no plugin for
    monkeypatch.setattr(mb, "_bsdf_dict", lambda bsdf: d)
    with pytest.raises(ValueError, match="no Mitsuba counterpart"):
        mb.to_mitsuba(object(), 550)


@pytest.mark.parametrize("break_it, expect", [
    # forgetting that Mitsuba's conductor index is relative to the outside medium
    (lambda p: {**p, "eta": p["eta"] * 1.33, "k": p["k"] * 1.33}, "weight"),
    # the dielectric seen from the other side: transmission weights and lobe choice change
    (lambda p: {**p, "int_ior": p["ext_ior"], "ext_ior": p["int_ior"]}, "any"),
    # a 1e-4 change of the albedo
    (lambda p: {**p, "reflectance": p["reflectance"] * (1 + 1e-4)}, "eval"),
])
def test_09_the_harness_catches_mismatches(monkeypatch, break_it, expect):
    convert = mb.to_mitsuba
    monkeypatch.setattr(mb, "to_mitsuba", lambda bsdf, wl=None: break_it(convert(bsdf, wl)))
    bsdf = {"weight": Conductor(eta=1.7, k=2.3, ext_ior=1.33), "any": Dielectric(1.5, 1.0),
            "eval": Diffuse(0.5)}[expect]
    c = mb.compare_bsdf(bsdf, n_pairs=1000)
    assert not c.passed
    if expect != "any":
        assert c.max_error[expect] > TARGET


def test_10_queries_cover_both_sides_grazing_and_the_critical_angle():
    eta = 1.5
    q = draw_queries(1000, seed=0, critical=(eta, -1))
    assert 450 <= np.sum(q.wi[:, 2] > 0) <= 550  # both sides (near-critical ones lie below)
    assert np.sum(np.abs(q.wi[:, 2]) < 1e-2) >= 50 and np.sum(np.abs(q.wo[:, 2]) < 1e-2) >= 50
    cos2 = 1 - eta**2 * (1 - q.wi[:, 2] ** 2)
    inside = q.wi[:, 2] < 0
    assert np.sum(inside & (np.abs(cos2) < 1e-3)) >= 5
    for a in (q.wi, q.wo, q.u1, q.u2):  # float32-exact, so both codes see the same inputs
        assert np.array_equal(a, a.astype(np.float32).astype(np.float64))
    assert np.all(q.wi[:, 2] != 0)


def test_11_variant():
    v = variant()
    assert v in VARIANTS
    assert mitsuba().variant() == v


def test_12_lobe_flags_map_to_bsdflab_lobes():
    from bsdflab.reference.mitsuba_calls import lobe_of_flags

    f = mitsuba().BSDFFlags
    got = lobe_of_flags(np.array([int(f.DiffuseReflection), int(f.DeltaReflection),
                                  int(f.DeltaTransmission), int(f.Null)]))
    assert list(got) == [Lobe.DIFFUSE_REFLECTION, Lobe.DELTA_REFLECTION,
                         Lobe.DELTA_TRANSMISSION, -1]
