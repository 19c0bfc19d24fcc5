"""Property-based fuzzing of the public API (hypothesis): every call must end in exactly
one of two outcomes -- a ValueError (bad input, clearly refused) or finite outputs of the
documented shape. Anything else (another exception, NaN, inf, a wrong shape) fails.

Inputs mix plausible values with hostile ones: NaN, infinities, denormals, huge Python
integers, bools, strings, nested containers, extreme indices and thicknesses. Examples are
derandomised (a fixed seed), so CI runs the same cases every time; the ``slow`` variant
runs many more. The counts (cases, clean errors, other outcomes) are printed at the end of
the module and stored in pytest's cache under ``bsdflab/fuzz_counts`` (and written to
``$BSDFLAB_FUZZ_REPORT`` when set) for the closing notes.
"""
from __future__ import annotations

import json
import math
import os
from collections import Counter

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import bsdflab as bl
from bsdflab import optics, presets
from bsdflab.render import Camera, Scene
from bsdflab.render.geometry import build_mesh
from bsdflab.tables import TableGrid

FAST_EXAMPLES = 250   # per property in CI: ~1500 cases, ~20 s on 2 loaded cores
SLOW_EXAMPLES = 3000
COUNTS: Counter = Counter()

# -- hostile and plausible values ----------------------------------------------------------
NASTY_FLOATS = [math.nan, math.inf, -math.inf, 0.0, -0.0, 5e-324, 1e-320, 1e-200, 1e-3,
                1e3, 3e38, 1e200, 1e308, -1.0, 1.0000000001]
NASTY_INTS = [0, -1, 1, 2**31, 2**63, 2**64, 10**400, -(10**400)]
JUNK = [None, "1.5", b"x", [], {}, [[1.0]], {"type": []}, True, object()]

reals = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                  st.floats(0.01, 10.0), st.sampled_from(NASTY_FLOATS))
anything = st.one_of(reals, st.sampled_from(NASTY_INTS), st.integers(-5, 40), st.sampled_from(JUNK))


def mostly(good):
    """``good`` nine times in ten, otherwise anything at all (an explicit weight: one_of's
    branch choice is not uniform under hypothesis's search)."""
    return st.integers(0, 9).flatmap(lambda k: anything if k == 0 else good)


iors = mostly(st.one_of(st.floats(1.0, 3.0), st.floats(1.0, 3.0), st.floats(1e-4, 1e4)))
alphas = mostly(st.floats(1e-4, 1.0))
wavelength_sets = mostly(st.one_of(st.none(), st.lists(st.floats(300.0, 900.0), min_size=1, max_size=4),
                                   st.lists(reals, min_size=1, max_size=3)))
thicknesses = mostly(st.one_of(st.none(), st.floats(0.0, 2000.0)))


@st.composite
def direction_arrays(draw, n=None):
    """(N, 3) directions: mostly unit vectors (some below the surface, some grazing),
    sometimes hostile."""
    if draw(st.integers(0, 19)) == 0:
        return draw(st.one_of(anything, st.lists(st.lists(reals, min_size=3, max_size=3), min_size=1, max_size=3)))
    n = draw(st.integers(1, 4)) if n is None else n
    rows = []
    for _ in range(n):
        theta = draw(st.floats(0.0, math.pi))
        phi = draw(st.floats(0.0, 2 * math.pi))
        rows.append([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
    return np.array(rows)


films = mostly(st.one_of(st.none(), st.fixed_dictionaries({"material": iors, "thickness_nm": thicknesses}),
                         st.lists(st.fixed_dictionaries({"material": st.floats(1.2, 2.0),
                                                         "thickness_nm": st.floats(0.0, 800.0)}), max_size=3)))


@st.composite
def models(draw):
    """(constructor name, thunk) for one public model construction."""
    kind = draw(st.sampled_from(["diffuse", "conductor", "metal", "dielectric", "roughdielectric",
                                 "roughconductor", "layered", "from_dict"]))
    if kind == "diffuse":
        r = draw(mostly(st.one_of(st.floats(0.0, 1.0), st.lists(st.floats(0.0, 1.0), min_size=3, max_size=3))))
        two_sided = draw(mostly(st.booleans()))
        return kind, lambda: bl.Diffuse(r, two_sided=two_sided)
    if kind == "conductor":
        eta, k, ext = draw(iors), draw(mostly(st.floats(0.0, 5.0))), draw(iors)
        return kind, lambda: bl.Conductor(eta=eta, k=k, ext_ior=ext)
    if kind == "metal":
        material = draw(st.sampled_from(["Au", "Ag", "Cu", "Al", "none", "Unobtainium", 3, None]))
        film = draw(films)
        return kind, lambda: bl.Conductor(material=material, film=film)
    if kind == "dielectric":
        a, b, film = draw(iors), draw(iors), draw(films)
        return kind, lambda: bl.Dielectric(a, b, film=film)
    if kind == "roughdielectric":
        alpha, a, b = draw(alphas), draw(iors), draw(iors)
        return kind, lambda: bl.RoughDielectric(alpha, int_ior=a, ext_ior=b)
    if kind == "roughconductor":
        alpha, eta = draw(alphas), draw(iors)
        return kind, lambda: bl.RoughConductor(alpha, eta=eta, k=1.0)
    if kind == "layered":
        top = {"type": "roughdielectric", "alpha": draw(st.floats(0.01, 0.5)), "int_ior": 1.5, "ext_ior": 1.0}
        slab = {"thickness_um": draw(mostly(st.floats(0.0, 10.0))),
                "sigma_a": draw(mostly(st.floats(0.0, 2.0))), "sigma_s": draw(mostly(st.floats(0.0, 2.0)))}
        samples = draw(mostly(st.integers(1, 8)))
        seed = draw(mostly(st.integers(0, 2**64 - 1)))
        depth = draw(mostly(st.integers(1, 64)))
        return kind, lambda: bl.Layered([top], [slab], {"type": "diffuse", "reflectance": 0.5},
                                        samples=samples, seed=seed, max_depth=depth)
    d = draw(st.one_of(st.dictionaries(st.sampled_from(["type", "alpha", "int_ior", "reflectance", "eta"]),
                                       anything, max_size=4),
                       st.fixed_dictionaries({"type": st.sampled_from(["diffuse", "dielectric", "plastic", 3, []])}),
                       anything))
    return kind, lambda: bl.from_dict(d)


# -- the two outcomes ------------------------------------------------------------------------
def outcome(call, check):
    """Run ``call``; a ValueError is a clean refusal, a result must pass ``check``."""
    COUNTS["cases"] += 1
    try:
        result = call()
    except ValueError as e:
        assert str(e) and "\n" not in str(e).strip(), f"error message is not one line: {e!r}"
        COUNTS["clean errors"] += 1
        return None
    except Exception as e:  # anything else is a finding
        COUNTS["other outcomes"] += 1
        raise AssertionError(f"{type(e).__name__} instead of ValueError: {e}") from e
    try:
        check(result)
    except AssertionError:
        COUNTS["other outcomes"] += 1
        raise
    COUNTS["finite results"] += 1
    return result


def finite(a, shape=None):
    a = np.asarray(a)
    assert np.all(np.isfinite(a)), "non-finite output"
    if shape is not None:
        assert a.shape == shape, f"shape {a.shape}, expected {shape}"


def constructed(_):
    pass


def channels_of(wavelengths) -> int:
    return 3 if wavelengths is None else np.size(wavelengths)


# -- properties ---------------------------------------------------------------------------------
def _models_and_methods(data):
    _, make = data.draw(models())
    model = outcome(make, constructed)
    if model is None:
        return
    n = data.draw(st.integers(1, 4))
    wi = data.draw(direction_arrays(n))
    wo = data.draw(st.one_of(direction_arrays(n), direction_arrays(n), direction_arrays(1), direction_arrays()))
    wl, t = data.draw(wavelength_sets), data.draw(thicknesses)
    lobes = data.draw(mostly(st.sampled_from([int(bl.Lobe.ALL), int(bl.Lobe.REFLECTION), 0])))
    n = max(len(np.atleast_2d(wi)) if isinstance(wi, np.ndarray) else 1,
            len(np.atleast_2d(wo)) if isinstance(wo, np.ndarray) else 1)
    outcome(lambda: model.eval(wi, wo, wavelengths=wl, lobes=lobes, thickness_nm=t),
            lambda v: finite(v, (n, channels_of(wl))))
    outcome(lambda: model.pdf(wi, wo, lobes=lobes, thickness_nm=t), lambda v: finite(v, (n,)))
    seed = data.draw(mostly(st.integers(0, 2**64 - 1)))
    m = len(wi) if isinstance(wi, np.ndarray) else 1

    def sampled(s):
        finite(s.wo, (m, 3)), finite(s.weight, (m, channels_of(wl))), finite(s.pdf, (m,))
        finite(s.eta, (m,))

    outcome(lambda: model.sample(wi, seed=seed, wavelengths=wl, lobes=lobes, thickness_nm=t), sampled)


def _optics(data):
    n0, n1, n2 = data.draw(iors), data.draw(iors), data.draw(iors)
    d, wl = data.draw(mostly(st.floats(0.0, 1000.0))), data.draw(
        mostly(st.one_of(st.floats(300.0, 900.0), st.lists(st.floats(300.0, 900.0), min_size=1, max_size=3))))
    cos = data.draw(mostly(st.floats(0.0, 1.0)))
    pol = data.draw(mostly(st.sampled_from(["s", "p", "unpolarised"])))
    def documented(r):  # the broadcast shape of the wavelengths, the angle and the thickness
        finite(r, np.broadcast_shapes(*(np.shape(np.asarray(x, dtype=float)) for x in (wl, cos, d))))
        assert np.all((r >= 0) & (r <= 1 + 1e-12)), "reflectance outside [0, 1]"

    outcome(lambda: optics.film_reflectance((n0, n1, d, n2), wl, cos_theta=cos, polarisation=pol), documented)
    outcome(lambda: optics.fresnel_reflectance(cos, n0, n1), lambda r: [finite(x) for x in r])


def _presets_and_containers(data):
    which = data.draw(st.sampled_from(["stack", "melanin", "film", "grid", "camera", "scene", "mesh", "preset"]))
    a, b = data.draw(mostly(st.floats(0.1, 50.0))), data.draw(mostly(st.floats(1.0, 90.0)))
    # every draw happens before the call: a draw inside it could end the example mid-case
    k = data.draw(mostly(st.integers(-3, 600)))
    if which == "stack":
        outcome(lambda: presets.iridophore_stack(k, a, 100.0), lambda layers: None)
    elif which == "melanin":
        outcome(lambda: presets.melanin_absorption(a, b).at(bl.DEFAULT_WAVELENGTHS),
                lambda v: finite(v, bl.DEFAULT_WAVELENGTHS.shape))
    elif which == "film":
        outcome(lambda: presets.guanine_film(a), lambda layers: None)
    elif which == "grid":
        outcome(lambda: TableGrid(k, 4, 3, a if isinstance(a, list) else ()), lambda g: None)
    elif which == "camera":
        outcome(lambda: Camera(fov_deg=a, width=k), lambda c: None)
    elif which == "scene":
        shape = {"geometry": {"type": "sphere", "radius": a}, "emission": [1, 1, 1]}
        outcome(lambda: Scene.from_dict({"camera": {"fov_deg": b}, "shapes": [shape]}), lambda s: None)
    elif which == "mesh":
        spec = data.draw(st.sampled_from([
            {"type": "sphere", "radius": a, "subdivisions": k},
            {"type": "torus", "major_radius": 1.0, "minor_radius": a, "resolution": 8},
            {"type": "disk", "radius": a, "resolution": k},
            {"type": "rectangle", "size": [a, 1.0]}]))
        outcome(lambda: build_mesh(spec), lambda m: finite(m.positions))
    else:
        name = data.draw(st.sampled_from([*presets.PRESETS, "nope", 3]))
        outcome(lambda: presets.preset(name, **({"samples": a} if name == "xenopeltis" else {})), lambda m: None)


FUZZ_SETTINGS = dict(deadline=None, derandomize=True, database=None,
                     suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                            HealthCheck.filter_too_much])
PROPERTIES = [_models_and_methods, _optics, _presets_and_containers]


MIN_FINITE_SHARE = 0.1   # an API that refused (nearly) everything would pass the two outcomes


def run_counted(prop, **hypothesis_settings) -> None:
    """Run the property; then at least MIN_FINITE_SHARE of its cases must have answered."""
    before = Counter(COUNTS)

    def case(data):  # a fresh function: hypothesis refuses to set a function's settings twice,
        prop(data)   # and the fast and slow variants run the same property in one session

    given(st.data())(settings(**hypothesis_settings)(case))()
    cases, finite_results = COUNTS["cases"] - before["cases"], COUNTS["finite results"] - before["finite results"]
    assert cases > 0 and finite_results >= MIN_FINITE_SHARE * cases, (
        f"{prop.__name__}: only {finite_results} of {cases} cases gave a result")


@pytest.mark.parametrize("prop", PROPERTIES, ids=lambda f: f.__name__.strip("_"))
def test_public_api_refuses_cleanly_or_answers_finitely(prop):
    run_counted(prop, max_examples=FAST_EXAMPLES, **FUZZ_SETTINGS)


@pytest.mark.slow
@pytest.mark.parametrize("prop", PROPERTIES, ids=lambda f: f.__name__.strip("_"))
def test_public_api_refuses_cleanly_or_answers_finitely_long(prop):
    run_counted(prop, max_examples=SLOW_EXAMPLES, derandomize=False,
                **{k: v for k, v in FUZZ_SETTINGS.items() if k != "derandomize"})


@pytest.fixture(scope="module", autouse=True)
def report_counts(request):
    yield
    counts = {k: COUNTS[k] for k in ("cases", "clean errors", "finite results", "other outcomes")}
    if getattr(request.config, "cache", None) is not None:
        request.config.cache.set("bsdflab/fuzz_counts", counts)
    if os.environ.get("BSDFLAB_FUZZ_REPORT"):
        with open(os.environ["BSDFLAB_FUZZ_REPORT"], "w") as f:
            json.dump(counts, f)
    reporter = request.config.pluginmanager.get_plugin("terminalreporter")
    capture = request.config.pluginmanager.get_plugin("capturemanager")
    if reporter is not None and capture is not None:
        with capture.global_and_fixture_disabled():
            reporter.write_line(f"\nbsdflab fuzz counts: {counts}")
