"""Bad input: Python raises a ValueError naming the parameter; the core never crashes."""
import numpy as np
import pytest

import bsdflab as bl
from bsdflab import _core, optics, presets
from bsdflab.tables import TableBSDF, TableGrid

UP = np.array([0.0, 0.0, 1.0])


@pytest.mark.parametrize("make, match", [
    (lambda: bl.Diffuse(-0.1), "reflectance must be >= 0"),
    (lambda: bl.Diffuse(1.5), "reflectance must be <= 1"),
    (lambda: bl.Diffuse([0.2, 1.2, 0.3]), "reflectance"),
    (lambda: bl.Diffuse(np.nan), "reflectance must be finite"),
    (lambda: bl.Diffuse("red"), "reflectance"),
    (lambda: bl.Conductor(material="Unobtainium"), "unknown metal"),
    (lambda: bl.Conductor(eta=-1.0, k=2.0), "eta must be >= 0.001"),
    (lambda: bl.Conductor(eta=1.0, k=-2.0), "k must be >= 0"),
    (lambda: bl.Conductor(material="Au", eta=1.0), "either material"),
    (lambda: bl.Conductor(ext_ior=0.0), "ext_ior must be >= 0.001"),
    (lambda: bl.Dielectric(int_ior=0.0), "int_ior must be >= 0.001"),
    (lambda: bl.Dielectric(int_ior=np.inf), "int_ior must be finite"),
    (lambda: bl.Dielectric(ext_ior=-1.5), "ext_ior must be >= 0.001"),
    (lambda: bl.from_dict({"type": "plastic"}), "unknown BSDF type"),
    (lambda: bl.from_dict({"int_ior": 1.5}), "'type'"),
    (lambda: bl.from_dict({"type": "dielectric", "colour": 3}), "bad parameters"),
])
def test_01_bad_parameters(make, match):
    with pytest.raises(ValueError, match=match):
        make()


@pytest.mark.parametrize("wi, wo, match", [
    (np.zeros((4, 2)), np.zeros((4, 3)), "wi must have shape"),
    (np.array([[0, 0, 2.0]]), UP, "unit vectors"),
    (np.array([[0, 0, np.nan]]), UP, "finite"),
    (UP, np.array([[0, 0, 1.0], [0, 0, 0.0]]), "unit vectors"),
    (np.tile(UP, (3, 1)), np.tile(UP, (2, 1)), "same length"),
    (UP, "up", "wo must be"),
])
def test_02_bad_directions(wi, wo, match):
    with pytest.raises(ValueError, match=match):
        bl.Diffuse(0.5).eval(wi, wo)


def test_03_bad_sample_arguments():
    d = bl.Diffuse(0.5)
    with pytest.raises(ValueError, match="u1 must have shape"):
        d.sample(np.tile(UP, (3, 1)), u1=np.zeros(2), u2=np.zeros((3, 2)))
    with pytest.raises(ValueError, match="u2 must be <= 1"):
        d.sample(UP, u1=[0.5], u2=[[0.5, 1.5]])
    with pytest.raises(ValueError, match="seed"):
        d.sample(UP, seed=-1)
    with pytest.raises(ValueError, match="lobes"):
        d.eval(UP, UP, lobes=1 << 9)
    with pytest.raises(ValueError, match="wavelengths must be >= 1"):
        d.eval(UP, UP, wavelengths=[0.0])


CORES = [
    _core.Diffuse([500.0], [0.5], False), _core.Diffuse([500.0], [0.5], True),
    _core.SmoothInterface([500.0], _core.ConductorTerm([0.2 + 3j], 1.0), True),
    _core.SmoothInterface([500.0], _core.DielectricTerm(1, 1.5, 1.0), False),
    _core.RoughInterface([500.0], _core.ConductorTerm([0.2 + 3j], 1.0), 0.3, True),
    _core.RoughInterface([500.0], _core.DielectricTerm(1, 1.5, 1.0), 0.3, False),
    _core.RoughInterface([500.0], _core.FilmTerm([500.0], 1.0, [[1.8 + 0.1j]], [400.0], [1.5], True), 0.3, False),
]


@pytest.mark.parametrize("core", CORES)
def test_04_core_tolerates_degenerate_directions(core):
    bad = np.array([[np.nan, 0, 1], [0, 0, np.inf], [0, 0, 0], [1, 0, 0], [0, 0, -np.inf],
                    [1e300, 1e300, 1e300], [0, 0, 1e-300]], dtype=float)
    good = np.tile([0.0, 0.6, 0.8], (len(bad), 1))
    for wi, wo in ((bad, good), (good, bad), (bad, bad)):
        assert np.all(core.eval(wi, wo) == 0)
        assert np.all(core.pdf(wi, wo) == 0)
    wo, weight, pdf, lobe, eta = core.sample(bad, np.full(len(bad), 0.5), np.full((len(bad), 2), 0.5))
    assert np.all(lobe == 0) and np.all(weight == 0) and np.all(np.isfinite(wo))
    # out-of-range uniforms (the core's callers may pass anything) never produce NaN
    u1 = np.array([np.nan, -1.0, 2.0])
    u2 = np.array([[np.nan, 0.5], [-3, 7], [0.5, np.inf]])
    wo, weight, pdf, lobe, eta = core.sample(good[:3], u1, u2)
    assert np.all(np.isfinite(weight)) and np.all(np.isfinite(pdf))


# Python ints beyond float range, wrong types and unbounded counts (old: TypeError, OverflowError
# or silently accepted; noted beside each).
HUGE = 10**400


@pytest.mark.parametrize("call", [
    lambda: bl.Diffuse(HUGE), lambda: bl.Dielectric(HUGE), lambda: bl.RoughDielectric(HUGE),
    lambda: bl.Conductor(eta=HUGE), lambda: bl.Slab(HUGE), lambda: bl.PhaseFunction("hg", g=HUGE),
    lambda: bl.Diffuse(0.5).eval([HUGE, 0, 1], UP), lambda: bl.Diffuse(0.5).eval(UP, UP, wavelengths=[HUGE]),
    lambda: bl.Diffuse(0.5).eval(UP, UP, lobes=HUGE), lambda: bl.Diffuse(0.5).eval(UP, UP, lobes=float("inf")),
    lambda: bl.Dielectric(film=[{"material": 1.5, "thickness_nm": 100}]).eval(UP, UP, thickness_nm=HUGE),
    lambda: optics.film_reflectance((1.0, 1.5, HUGE, 1.5), 550.0, 0.3),
    lambda: optics.fresnel_reflectance(0.5, HUGE, 1.5),
    lambda: bl.Diffuse(0.5).sample(UP, seed=2**64),                       # old: pybind TypeError
    lambda: bl.Layered([bl.Dielectric()], [bl.Slab()], bl.Diffuse(), samples=2**31),  # old: accepted
    lambda: bl.Layered([bl.Dielectric()], [bl.Slab()], bl.Diffuse(), max_depth=2**40),
    lambda: bl.from_dict({"type": []}),                                   # old: TypeError
    lambda: bl.from_dict({"type": "diffuse", 3: 1}),
    lambda: bl.Conductor(material=["Au"]),
    lambda: bl.Diffuse(0.5, two_sided="no"),
    lambda: presets.iridophore_stack(float("nan")),                       # old: TypeError
    lambda: presets.iridophore_stack(-5),                                 # old: silently no film
    lambda: presets.iridophore_stack(10**7),                              # old: a 20-million list first
    lambda: presets.melanin_absorption({}),                               # old: TypeError
    lambda: presets.melanin_absorption(1.2, HUGE),
    lambda: presets.preset("xenopeltis", colour=1),
    lambda: TableBSDF(4.0),                                               # old: TypeError
    lambda: TableGrid(3, 5, 4, "abc"),
    lambda: TableGrid.from_dict([1, 2]),
])
def test_05_bad_input_of_the_wrong_kind_is_a_one_line_value_error(call):
    with pytest.raises(ValueError) as info:
        call()
    assert "\n" not in str(info.value) and len(str(info.value)) < 400


def test_06_layered_samples_bound_is_the_core_s():
    walks = bl.Layered([bl.Dielectric()], [bl.Slab()], bl.Diffuse(), samples=1 << 24)  # the top is fine
    assert walks.samples == 1 << 24
