"""Structure fits (bsdflab.fit.structure, instrument, stack_forward, stack_posterior) against
independent references: the stack's reflectance against ``tmm``; the instrument's slit and
cone averages against dense numpy quadratures; recovery of a structure + instrument from
data made by tmm with the instrument applied in numpy (tests/support/stack_data.py)."""
from __future__ import annotations

import numpy as np
import pytest
import tmm

from bsdflab.fit.data import Dataset
from bsdflab.fit.materials import NAMED, material
from bsdflab.fit.sampling import run_sampler
from bsdflab.fit.stack_config import StackConfig
from bsdflab.fit.stack_forward import StackForward
from bsdflab.fit.stack_posterior import StackPosterior
from bsdflab.fit.structure import Structure
from support.stack_data import INSTRUMENT_PRIORS, smeared, synthetic, two_layer_config, two_layer_media


def specular(angles, wavelengths) -> Dataset:
    n = len(angles) * len(wavelengths)
    return Dataset(np.zeros(n, int), np.repeat(np.asarray(angles, float), len(wavelengths)), np.full(n, np.nan),
                   np.tile(np.asarray(wavelengths, float), len(angles)), np.zeros(n), np.ones(n))


def defaults(structure):
    d = {p.name: p.default for p in structure.parameters()}
    return lambda name: np.array([d[name]])


STRUCTURES = {
    # film above the substrate's index, dispersive substrate
    "guanine on keratin": {"substrate": "keratin", "layers": [
        {"name": "film", "material": "guanine", "thickness_nm": 430.0}]},
    # film below the substrate's index (an anti-reflection layer), absorbing substrate
    "low film on eumelanin": {"substrate": "eumelanin", "layers": [
        {"name": "film", "material": {"cauchy": [1.38, 3000.0]}, "thickness_nm": 120.0}]},
    # a periodic iridophore stack with a water gap and an absorbing layer
    "periodic": {"exterior": "water", "substrate": "chitin", "layers": [
        {"name": "top", "material": {"n": 1.6, "k": 0.02}, "thickness_nm": 60.0},
        {"periods": 5, "layers": [{"name": "plate", "material": "guanine", "thickness_nm": 80.0},
                                  {"name": "gap", "material": "cytoplasm", "thickness_nm": 110.0}]}]},
    "bare": {"substrate": {"n": 1.5, "k": 0.3}},
    # every medium non-dispersive: the core's film_stack_spectrum path (interfaces reused)
    "constant periodic": {"substrate": {"n": 1.55, "k": 0.01}, "layers": [
        {"periods": 4, "layers": [{"name": "plate", "material": "guanine", "thickness_nm": 90.0},
                                  {"name": "gap", "material": "cytoplasm", "thickness_nm": 130.0}]}]},
    "constant film": {"substrate": {"n": 1.55}, "layers": [
        {"name": "film", "material": "guanine", "thickness_nm": 700.0}]},
}


@pytest.mark.parametrize("key", STRUCTURES)
def test_stack_matches_tmm(key):
    """The C++ stack (film_stack folds) against tmm's transfer matrices: both exact, so
    agreement to round-off (1e-12 absolute; R <= 1). Mutation caught: the layers passed
    bottom-up (the stack reversed) misses by > 1e-2 in the multilayer cases."""
    s = Structure.parse(STRUCTURES[key])
    angles, wls = [0.0, 20.0, 45.0, 70.0, 85.0], [360.0, 450.0, 555.0, 640.0, 990.0]
    got = StackForward(specular(angles, wls), s).exact(defaults(s), [0.0], [0.0], [0.0])[0]
    media = [s.exterior, *(s.layers[i] for i in s.order), s.substrate]
    d = [s.thickness_nm[i] for i in s.order]
    ref = []
    for a in angles:
        for w in wls:
            n = [complex(m.material.index({}, np.array([[w]]))[0, 0]) for m in media]
            ref.append(tmm.unpolarized_RT(n, [np.inf, *d, np.inf], np.radians(a), w)["R"])
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12)


def test_bandwidth_matches_dense_convolution():
    """The slit's Gauss-Hermite average (7 nodes, the default) against a 0.25 nm trapezoid
    convolution of tmm spectra, FWHM 20 nm over fringes ~90 nm apart. Tolerance 3e-6: measured
    9.0e-7 at 7 nodes (7.6e-9 at 9, 1.2e-10 at 15, the reference's own floor).
    Mutation caught: reading the FWHM as the Gaussian's sd (misses by 3.5e-2)."""
    s = Structure.parse(two_layer_config({})["structure"])
    wls = np.array([420.0, 505.0, 590.0, 680.0])
    ds = specular([30.0], wls)
    values = {"film_thickness_nm": 900.0, "gap_thickness_nm": 150.0, "film_ior": 1.83, "film_k": 0.0,
              "substrate_ior": 1.532, "substrate_cauchy_b": 5890.0, "substrate_k": 0.0}
    got = StackForward(ds, s).exact(lambda n: np.array([values[n]]), [0.0], [0.0], [20.0])[0]
    ref = smeared(two_layer_media(1.83, 1.532), [900.0, 150.0], 30.0, wls, 20.0)
    np.testing.assert_allclose(got, ref, rtol=0, atol=3e-6)
    unsmeared = smeared(two_layer_media(1.83, 1.532), [900.0, 150.0], 30.0, wls, 0.0)
    assert np.max(np.abs(unsmeared - ref)) > 1e-2  # the slit matters at this bandwidth


@pytest.mark.parametrize("fwhm", [4.0, 12.0, 30.0])
def test_bandwidth_on_a_uniform_grid_matches_dense_convolution(fwhm):
    """Evenly spaced wavelengths take the shared-grid slit (_core.smear_uniform) for
    FWHM >= 3.5 nm at a 5 nm step: against the 0.25 nm trapezoid convolution of tmm spectra.
    Tolerance 1e-7: measured <= 3.4e-8 (the 4.5 sigma truncation), vs 9e-7 for the 7 Gauss-
    Hermite nodes it replaces. Mutation caught: the kernel sampled at the data step h instead
    of the grid step h / m (misses by > 1e-3)."""
    s = Structure.parse(two_layer_config({})["structure"])
    wls = np.arange(400.0, 451.0, 5.0)
    values = {"film_thickness_nm": 900.0, "gap_thickness_nm": 150.0, "film_ior": 1.83, "film_k": 0.0,
              "substrate_ior": 1.532, "substrate_cauchy_b": 5890.0, "substrate_k": 0.0}
    f = StackForward(specular([30.0], wls), s)
    assert f._step == 5.0
    got = f.exact(lambda n: np.array([values[n]]), [0.0], [0.0], [fwhm])[0]
    ref = smeared(two_layer_media(1.83, 1.532), [900.0, 150.0], 30.0, wls, fwhm)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-7)


def fresnel_unpolarised(n, cos_i):
    """Unpolarised Fresnel reflectance from air into index n (numpy, independent of the core)."""
    sin2 = 1 - cos_i**2
    cos_t = np.sqrt(n**2 - sin2 + 0j) / n
    rs = (cos_i - n * cos_t) / (cos_i + n * cos_t)
    rp = (n * cos_i - cos_t) / (n * cos_i + cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


@pytest.mark.parametrize("theta, cone", [(60.0, 8.0), (10.0, 15.0), (75.0, 10.0), (30.0, 20.0)])
def test_acceptance_matches_dense_cone_average(theta, cone):
    """The cone average (4 x 6 nodes) of a bare interface against a 400 x 800 midpoint rule
    over the cone in solid angle (numpy Fresnel). Tolerance 2e-7 (measured <= 9.2e-8, at
    75 deg, where the Fresnel curve bends most; the cone itself moves R by 1e-4 to 3e-2).
    Mutation caught: weights uniform in the cone angle b instead of sin b (misses by
    3.7e-5 to 9.5e-3)."""
    s = Structure.parse({"exterior": {"n": 1.0}, "substrate": {"n": 1.5}})
    values = {"exterior_ior": 1.0, "substrate_ior": 1.5, "substrate_k": 0.0}
    got = StackForward(specular([theta], [500.0]), s).exact(lambda n: np.array([values[n]]), [0.0], [cone], [0.0])
    b = (np.arange(400) + 0.5) / 400 * np.radians(cone)
    psi = (np.arange(800) + 0.5) / 800 * 2 * np.pi
    B, PSI = np.meshgrid(b, psi, indexing="ij")
    t = np.radians(theta)
    cos_i = np.abs(np.cos(t) * np.cos(B) + np.sin(t) * np.sin(B) * np.cos(PSI))
    w = np.sin(B)
    ref = np.sum(w * fresnel_unpolarised(1.5, cos_i)) / np.sum(w)
    assert abs(got[0, 0] - ref) < 2e-7, (got[0, 0], ref)
    assert abs(fresnel_unpolarised(1.5, np.cos(t)) - ref) > 1e-4  # the cone matters


def test_offset_scale_background_and_domain():
    """Angle offset = the nominal angle moved; scale and background affine; a set outside
    the domain (negative thickness, offset past 90 deg) gives NaN rows, the others not."""
    s = Structure.parse(STRUCTURES["guanine on keratin"])
    f = StackForward(specular([30.0, 50.0], [450.0, 600.0]), s)
    f2 = StackForward(specular([32.5, 52.5], [450.0, 600.0]), s)
    v = defaults(s)
    np.testing.assert_allclose(f.exact(v, [2.5], [0.0], [0.0]), f2.exact(v, [0.0], [0.0], [0.0]), rtol=0, atol=1e-15)
    r = f.exact(v, [0.0], [0.0], [0.0])
    np.testing.assert_allclose(f.evaluate(v, [0.7], [0.02], [0.0], [0.0], [0.0]), 0.7 * r + 0.02, rtol=0, atol=1e-15)
    two = lambda name: np.repeat(v(name), 3)  # noqa: E731
    out = f.exact(two, [0.0, 45.0, 0.0], [0.0, 0.0, -1.0], [0.0, 0.0, 0.0])
    assert np.all(np.isfinite(out[0])) and np.all(np.isnan(out[2]))
    assert np.all(np.isfinite(out[1, :2])) and np.all(np.isnan(out[1, 2:]))  # 30 + 45 < 90 <= 50 + 45


TRUTH = dict(film_thickness_nm=900.0, gap_thickness_nm=150.0, film_ior=1.85, substrate_ior=1.54, scale=0.8,
             background=0.01, angle_offset_deg=1.5, bandwidth_nm=15.0)


def intervals(run, level=0.997):
    return np.quantile(run.draws(), [(1 - level) / 2, (1 + level) / 2], axis=0)


def test_recovery_of_structure_and_instrument_from_tmm_data():
    """Data: tmm spectra of air | film | gap | keratin-like substrate at 4 angles x 25
    wavelengths, seen through scale 0.8, background 0.01, angle offset 1.5 deg and a 15 nm
    slit, all applied in numpy (stack_support), 1 % + 0.002 noise, fixed seed. The fit
    (8 free: 2 thicknesses, 2 indices, 4 instrument) puts every truth inside its 99.7 %
    interval (for a calibrated posterior each misses with probability 0.003: the family's
    false alarm is 2.4 %, fixed by the seed).
    Power (the issue's mis-specified instrument): the same data fitted with the bandwidth
    ignored (fixed at 0) excludes at least two truths. Measured at 1000 steps it excludes
    four: gap thickness, scale and background by 1.8-2.6 interval widths, the angle offset by
    0.2; so its run is 500 steps (ESS ~400 at tau ~22: the interval's ends move by a few % of
    its width, not widths; 1000 before, ~4 CPU-s more)."""
    ds = synthetic(TRUTH, [15, 35, 55, 70], np.arange(400.0, 701.0, 12.5), seed=1)
    cfg = StackConfig.parse(two_layer_config(INSTRUMENT_PRIORS, walkers=20, max_steps=2000))
    post = StackPosterior([ds], cfg)
    lo, hi = intervals(run_sampler(post, cfg.sampler, progress=False))
    truth = np.array([TRUTH[n] for n in post.free])
    assert np.all((lo < truth) & (truth < hi)), list(zip(post.free, lo, truth, hi, strict=True))

    wrong = StackConfig.parse(two_layer_config({**INSTRUMENT_PRIORS, "bandwidth_nm": 0.0}, walkers=20,
                                               max_steps=500))
    post = StackPosterior([ds], wrong)
    lo, hi = intervals(run_sampler(post, wrong.sampler, progress=False))
    truth = np.array([TRUTH[n] for n in post.free])
    assert np.sum((truth < lo) | (truth > hi)) >= 2, list(zip(post.free, lo, truth, hi, strict=True))


def test_co_refinement_shares_the_structure():
    """Two datasets with their own instruments: the joint prediction is each dataset's own
    prediction (its scale, offset, bandwidth) from the one shared structure, and the joint
    log likelihood is the sum of the two."""
    base = two_layer_config({})
    del base["instrument"]
    base["dataset"] = [
        {"name": "spec", "data": "a.csv", "instrument": {"scale": {"prior": "uniform", "low": 0.5, "high": 1.5},
                                                         "bandwidth_nm": 5.0}},
        {"name": "sphere", "data": "b.csv", "instrument": {"scale": 0.9, "angle_offset_deg": 1.0,
                                                           "scale_per_series": True}}]
    cfg = StackConfig.parse(base)
    a, b = specular([20.0, 40.0], [450.0, 550.0, 650.0]), specular([8.0], [400.0, 500.0])
    post = StackPosterior([a, b], cfg)
    assert "spec.scale" in post.free and "sphere.scale_8" in post.config.fixed
    x = np.array([[900.0, 150.0, 1.85, 1.54, 0.7]])
    joint = post.predict(x)[0]
    s = cfg.structure
    vals = post.named(x)
    v = lambda n: vals[n]  # noqa: E731
    own_a = StackForward(a, s).evaluate(v, [0.7], [0.0], [0.0], [0.0], [5.0])[0]
    own_b = StackForward(b, s).evaluate(v, [0.9], [0.0], [1.0], [0.0], [0.0])[0]
    np.testing.assert_array_equal(joint, np.concatenate([own_a, own_b]))


def test_scale_per_series_keys_on_named_series():
    """``scale_per_series`` with rows that name their series (as ``bsdflab fit import`` writes
    them: one per file or sample): one scale per series, ``scale_<series>``, each applied to its
    own rows only, whatever their angles (mutation caught: keying on the angle, as for unnamed
    rows, would give one scale_20 for both series and break the per-row ratio); names that
    collide after lower-casing are refused."""
    from dataclasses import replace

    base = specular([20.0, 40.0], [450.0, 550.0, 650.0])
    two = replace(base, series=np.array(["Bird 1"] * 3 + ["bird-2"] * 3, dtype=object))
    c = two_layer_config({"scale": {"prior": "uniform", "low": 0.5, "high": 1.5}, "scale_per_series": True})
    post = StackPosterior([two], StackConfig.parse(c))
    assert post.free[-2:] == ("scale_bird_1", "scale_bird_2")
    structure = [900.0, 150.0, 1.85, 1.54]
    scaled = post.predict(np.array([[*structure, 0.7, 1.2]]))[0]
    plain = StackPosterior([base], StackConfig.parse(two_layer_config({"scale": {"prior": "uniform", "low": 0.5,
                                                                                 "high": 1.5}})))
    unscaled = plain.predict(np.array([[*structure, 1.0]]))[0]
    np.testing.assert_allclose(scaled / unscaled, np.repeat([0.7, 1.2], 3), rtol=1e-12, atol=0)
    clash = replace(base, series=np.array(["a b"] * 3 + ["a-b"] * 3, dtype=object))
    with pytest.raises(ValueError, match="do not give distinct parameter names"):
        StackPosterior([clash], StackConfig.parse(c))


@pytest.mark.parametrize("change, message", [
    (lambda c: c["structure"].update(substrate="unobtainium"), "unknown material 'unobtainium'"),
    (lambda c: c["structure"]["layers"].append({"name": "film", "material": "air", "thickness_nm": 1.0}),
     "used twice"),
    (lambda c: c["structure"]["layers"].append({"periods": 0, "layers": []}), "periods must be"),
    (lambda c: c["structure"].update(exterior="eumelanin"), "exterior must be lossless"),
    (lambda c: c["instrument"].update(bandwidth_nm=-1.0), "bandwidth_nm must be"),
    (lambda c: c["instrument"].update(slit=1.0), "unknown key(s) slit"),
    (lambda c: c["parameters"].update(film_index_A=1.8), "'film_index_A' is not a parameter"),
    (lambda c: c["structure"]["layers"][0].update(thickness_nm=-5.0), "thickness_nm must be"),
])
def test_config_errors_name_the_key(change, message):
    c = two_layer_config({"scale": 1.0})
    change(c)
    with pytest.raises(ValueError, match=None) as e:
        StackConfig.parse(c)
    assert message in str(e.value), str(e.value)


def test_named_materials():
    """Spot values of the cited dispersions (materials.py's sources)."""
    wl = np.array([[400.0, 550.0, 700.0]])
    np.testing.assert_allclose(NAMED["keratin"].index({}, wl).real, 1.532 + 5890 / wl**2, rtol=0, atol=1e-15)
    mel = NAMED["eumelanin"].index({}, wl)
    np.testing.assert_allclose(mel.imag, 0.56 * np.exp(-wl / 270.0), rtol=0, atol=1e-15)
    assert np.all(np.diff(mel.real) < 0) and np.all(np.diff(NAMED["water"].index({}, wl).real) < 0)
    free = material("x", {"cauchy": [1.5, 4000.0], "k": 0.01})
    got = free.index({"ior": np.array([1.6]), "cauchy_b": np.array([0.0]), "k": np.array([0.0])}, wl)
    np.testing.assert_allclose(got, np.full((1, 3), 1.6), rtol=0, atol=0)


def test_old_parameter_names_read_with_a_warning():
    """Issue 30's one vocabulary: the snake model's old names (film_index_A, sigma_a_550, ...)
    still read, mapped to the presets' names, with a FutureWarning that names the new one."""
    from bsdflab.fit.config import FitConfig

    with pytest.warns(FutureWarning) as caught:
        cfg = FitConfig.parse({"parameters": {"film_index_A": {"prior": "normal", "mean": 1.83, "sd": 0.05},
                                              "sigma_a_550": 1.0}})
    messages = [str(w.message) for w in caught]
    assert "[parameters] parameter 'film_index_A' is deprecated: it is now called 'film_ior'" in messages
    assert "[parameters] parameter 'sigma_a_550' is deprecated: it is now called 'pigment_absorption'" in messages
    assert "film_ior" in cfg.priors and cfg.fixed["pigment_absorption"] == 1.0


def test_structure_study_through_the_cli(tmp_path, capsys, monkeypatch):
    """`bsdflab fit - --config co.toml`: a config with a [structure] table writes the structure
    study folder, reading its [[dataset]] files (a short run: the folder, not the fit, is
    checked here) with its predictive checks and warnings (status 0 without --strict); a bad
    structure key is a one-line error naming it. One study, not two: the same run again
    under --overwrite --strict (status 3) cost another ~20 CPU-s of figures, and that branch
    of the report shared by both paths (bsdflab.cli.fit._report) is
    tests/fit/test_fit_checks.py::test_study_warns_loudly's.
    The bad key's error runs in-process (support.cli.cli_in_process: the same main(), without a
    child's ~2.5 CPU-s of imports); the study above is the real `bsdflab fit` process.
    Mutation: _report returning 3 on warnings without --strict fails it."""
    import json
    import shutil

    from support.cli import cli, cli_in_process, one_line_error

    shutil.copy("examples/fit/stack_data.csv", tmp_path / "a.csv")
    text = open("examples/fit/stack.toml", encoding="utf-8").read()
    text = text.replace("walkers = 20\nmax_steps = 8000",
                        "walkers = 20\nmax_steps = 20\ncheck_every = 10\nmap_starts = 1")
    co = text.replace("[instrument]", "[[dataset]]\nname = \"spec\"\ndata = \"a.csv\"\n[dataset.instrument]")
    (tmp_path / "co.toml").write_text(co)
    r = cli("fit", "-", "--config", str(tmp_path / "co.toml"), "--out", str(tmp_path / "co"), "--quiet")
    assert r.returncode == 0, r.stderr[-2000:]
    for name in ("parameters.md", "corner.png", "predictive.png", "residuals.png", "trace.png", "summary.json",
                 "draws.npz"):
        assert (tmp_path / "co" / name).is_file(), name
    summary = json.loads((tmp_path / "co" / "summary.json").read_text())
    assert summary["rows"] == 124 and "spec.bandwidth_nm" in summary["free"]
    # 20 steps cannot converge: the warning block on stderr, status 0 without --strict
    assert "NOT_CONVERGED" in [w["code"] for w in summary["warnings"]]
    assert "[NOT_CONVERGED]" in r.stderr and "posterior predictive checks" in r.stdout
    assert summary["predictive_checks"]["series"][1]["series"].startswith("spec: specular")

    (tmp_path / "bad.toml").write_text(text.replace('exterior = "air"', 'exterior = "vacuum"'))
    r = cli_in_process(capsys, monkeypatch, "fit", tmp_path / "a.csv", "--config", tmp_path / "bad.toml",
                       "--out", tmp_path / "b")
    one_line_error(r, "unknown material 'vacuum'")
