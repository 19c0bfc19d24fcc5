"""bsdflab.fit data files and TOML configs: round trips and clear ValueErrors for bad input."""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.fit import FitConfig, SimulationConfig, parse_csv, read_csv
from bsdflab.fit.config import load_toml
from bsdflab.fit.simulate import simulate

HEADER = "angle_deg,angle_out_deg,wavelength_nm,reflectance,sigma,geometry"
GOOD = [HEADER, "10,,500,0.05,0.001,specular", "0,45,500,0.01,0.001,diffuse", "8,,600,0.1,0.002,total"]


def test_round_trip(tmp_path):
    ds = parse_csv(["# a comment", *GOOD])
    path = tmp_path / "d.csv"
    ds.write_csv(path)
    back = read_csv(path)
    assert back.comments == ["a comment"]
    for field in ("geometry", "angle_deg", "wavelength_nm", "reflectance", "sigma"):
        np.testing.assert_array_equal(getattr(back, field), getattr(ds, field))
    assert np.isnan(back.angle_out_deg[0]) and back.angle_out_deg[1] == 45.0
    # angle_out_deg may be left out when nothing is diffuse
    assert len(parse_csv(["angle_deg,wavelength_nm,reflectance,sigma,geometry", "10,500,0.05,0.001,specular"])) == 1


@pytest.mark.parametrize("lines, match", [
    ([], "empty data file"),
    (["# only a comment"], "empty data file"),
    ([HEADER], "no data rows"),
    (["angle_deg,wavelength_nm,reflectance,geometry", "10,500,0.05,specular"], "missing \\['sigma'\\]"),
    ([HEADER, "10,,500,nan,0.001,specular"], "line 2: reflectance must be finite"),
    ([HEADER, "10,,500,0.05,0,specular"], "line 2: sigma must be > 0"),
    ([HEADER, "10,,500,0.05,-0.1,specular"], "sigma must be > 0"),
    ([HEADER, "10,,500,0.05,abc,specular"], "sigma must be a number"),
    ([HEADER, "10,,500,0.05,0.001,specular", "10,,500,0.06,0.001,specular"], "line 3: duplicate of line 2"),
    ([HEADER, "10,,200,0.05,0.001,specular"], "outside the model's range"),
    ([HEADER, "10,,1500,0.05,0.001,specular"], "outside the model's range"),
    ([HEADER, "10,,500,0.05,0.001,mirror"], "unknown geometry 'mirror'"),
    ([HEADER, "95,,500,0.05,0.001,specular"], "angle_deg must be in"),
    ([HEADER, "10,,500,0.05,0.001,diffuse"], "needs angle_out_deg"),
    ([HEADER, "10,10,500,0.05,0.001,diffuse"], "specular direction"),
    ([HEADER, "10,20,500,0.05,0.001,specular"], "must be empty"),
    ([HEADER, "10,,500,0.05,0.001"], "expected 6 values"),
])
def test_bad_data(lines, match):
    with pytest.raises(ValueError, match=match):
        parse_csv(lines, "x.csv")


def test_unreadable_file(tmp_path):
    with pytest.raises(ValueError, match="cannot read data file"):
        read_csv(tmp_path / "missing.csv")


def fit_toml(parameters: str, sampler: str = "walkers = 8") -> dict:
    import tomllib

    return tomllib.loads(f"[parameters]\n{parameters}\n[sampler]\n{sampler}\n")


def test_config_defaults_and_fixed():
    c = FitConfig.parse(fit_toml('film_thickness_nm = {prior = "uniform", low = 300, high = 600}\n'
                                 'film_ior = {fixed = 1.8}\nbase_albedo = 0.2'))
    assert c.free == ("film_thickness_nm",)
    assert c.fixed["film_ior"] == 1.8 and c.fixed["base_albedo"] == 0.2
    assert c.fixed["substrate_ior"] == pytest.approx(1.5515, abs=1e-4)  # preset default
    assert c.priors["film_thickness_nm"].logpdf(450.0) == pytest.approx(-np.log(300.0))


@pytest.mark.parametrize("params, sampler, match", [
    ('film_thickness = 3', "walkers = 8", "unknown parameter 'film_thickness'"),
    ('film_thickness_nm = {prior = "beta", a = 1}', "walkers = 8", "prior must be one of"),
    ('film_thickness_nm = {prior = "normal", mean = 400}', "walkers = 8", "missing \\['sd'\\]"),
    ('film_thickness_nm = {prior = "normal", mean = 400, sd = -1}', "walkers = 8", "sd must be > 0"),
    ('film_thickness_nm = {prior = "uniform", low = 600, high = 300}', "walkers = 8", "low must be < high"),
    ('film_thickness_nm = -5.0', "walkers = 8", "outside"),
    ('base_albedo = 0.5', "walkers = 8", "no free parameter"),
    ('film_thickness_nm = {prior = "uniform", low = 300, high = 600}', "walkers = 7", "even"),
    ('film_thickness_nm = {prior = "uniform", low = 300, high = 600}', "walkers = 0", "walkers must be an integer"),
    ('film_thickness_nm = {prior = "uniform", low = 300, high = 600}', "steps = 10", "unknown key"),
])
def test_bad_config(params, sampler, match):
    with pytest.raises(ValueError, match=match):
        FitConfig.parse(fit_toml(params, sampler))


def test_bad_toml_file(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text("[parameters\nx = 1\n")
    with pytest.raises(ValueError, match="not valid TOML"):
        load_toml(p)
    with pytest.raises(ValueError, match="cannot read config"):
        FitConfig.load(tmp_path / "none.toml")


def test_simulation_noise_model():
    import tomllib

    cfg = SimulationConfig.parse(tomllib.loads(
        "[truth]\nfilm_thickness_nm = 400.0\n[noise]\nrelative = 0.03\nabsolute = 0.001\nseed = 5\n"
        "[[measurement]]\ngeometry = 'specular'\nangles_deg = [10, 40]\n"
        "wavelengths_nm = {start = 400, stop = 700, step = 5}\n"))
    ds, y = simulate(cfg)
    np.testing.assert_allclose(ds.sigma, np.sqrt(0.001**2 + (0.03 * y) ** 2))
    z = (ds.reflectance - y) / ds.sigma
    # 122 standard normal residuals: mean within 4/sqrt(n), variance within 4 sd of chi2_n/n (sd sqrt(2/n))
    assert abs(z.mean()) < 4 / np.sqrt(len(z))
    assert abs(z.var() - 1) < 4 * np.sqrt(2 / len(z))
    again, _ = simulate(cfg)
    np.testing.assert_array_equal(again.reflectance, ds.reflectance)   # seeded
    assert any(c.startswith("SYNTHETIC") for c in ds.comments)
    with pytest.raises(ValueError, match="relative and absolute cannot both be 0"):
        SimulationConfig.parse({"noise": {"relative": 0.0, "absolute": 0.0},
                                "measurement": [{"geometry": "specular", "angles_deg": [1], "wavelengths_nm": [500]}]})
    with pytest.raises(ValueError, match="angle_pairs_deg"):
        SimulationConfig.parse({"measurement": [{"geometry": "diffuse", "angles_deg": [1], "wavelengths_nm": [500]}]})


@pytest.mark.parametrize("spec", [{"prior": "uniform", "low": 300.0, "high": 600.0},
                                  {"prior": "normal", "mean": 1.83, "sd": 0.05},
                                  {"prior": "lognormal", "median": 1.2, "sigma": 0.7},
                                  {"prior": "truncnormal", "mean": 0.3, "sd": 0.2, "low": 0.0, "high": 1.0}])
def test_prior_logpdf_matches_scipy(spec):
    from bsdflab.fit.priors import Prior

    prior = Prior.make("x", spec)
    lo, hi = prior.dist.ppf([1e-4, 1 - 1e-4])
    x = np.concatenate([np.linspace(lo, hi, 50), [lo - 1.0, hi + 1.0, -1.0, 0.0]])
    np.testing.assert_allclose(prior.logpdf(x), prior.dist.logpdf(x), rtol=1e-12, atol=1e-12)
