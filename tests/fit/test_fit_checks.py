"""The study's honest diagnostics: posterior predictive checks (power against a wrong model,
quiet on the right one), the warnings (bound, noise scale, step cap, thickness modes), the
stop reason stated as it is, and the warning block of the CLI. Small smooth-model fits
(8 walkers, a few hundred steps) with fixed seeds."""
from __future__ import annotations

import json

import numpy as np
import tomllib

from bsdflab.fit import FitConfig, LogPosterior, SimulationConfig, run_sampler, run_study, simulate
from bsdflab.fit.alerts import bound_alerts, conflict_alerts, draw_modes, mode_alerts, noise_alert
from bsdflab.fit.checks import ALPHA, predictive_checks, sidak_level
from bsdflab.fit.config import SamplerSettings
from bsdflab.fit.parameters import ALL_NAMES
from bsdflab.fit.priors import Prior
from bsdflab.fit.sampling import stop_reason
from support.cli import cli_in_process

TRUTH = """
[truth]
film_thickness_nm = 430.0
film_ior = 1.83
pigment_absorption = 0.4
base_albedo = 0.3
[noise]
relative = 0.02
absolute = 0.0002
seed = {seed}
[[measurement]]
geometry = "specular"
angles_deg = [15, 55]
wavelengths_nm = {{ start = 400, stop = 740, step = 20 }}
"""

FIT = """
[parameters]
film_thickness_nm = {{ prior = "normal", mean = 430.0, sd = 10.0 }}
film_ior = {{ prior = "normal", mean = 1.83, sd = 0.02 }}
pigment_absorption = 0.4
base_albedo = 0.3
{extra}
[model]
thickness_nodes = 1
[sampler]
walkers = 8
max_steps = {steps}
check_every = 100
seed = {seed}
map_starts = 2
"""

APPEARANCE = """
[appearance]
draws = 4
angles_deg = [0, 30]
renders = 0
"""


def data(seed, scale=1.0):
    d = simulate(SimulationConfig.parse(tomllib.loads(TRUTH.format(seed=seed))))[0]
    return d.with_reflectance(d.reflectance * scale)


def config(seed=0, steps=400, extra=""):
    return FitConfig.parse(tomllib.loads(FIT.format(seed=seed, steps=steps, extra=extra)))


def checks_of(dataset, seed):
    cfg = config(seed=seed)
    post = LogPosterior(dataset, cfg)
    run = run_sampler(post, cfg.sampler, progress=False)
    draws = run.draws()[::4]
    full = post.full(draws)
    return predictive_checks(dataset, post.predict(draws), full[:, ALL_NAMES.index("noise_scale")])


def test_predictive_check_flags_a_wrong_scale_and_is_quiet_on_the_right_model():
    """12 datasets of the right model and the same data scaled by 0.9 (a white-standard
    calibration the model lacks), fitted without a scale. At family-wise alpha = 0.01 the
    right model may raise a flag in <= 1 % of studies: P(>= 2 of 12) < 0.007, so 2 or more
    false alarms fail. Power: every one of the 12 scaled datasets is flagged (a 10 % scale
    against 2 % noise is ~5 sigma per row). The mutation caught: a check that ignores the
    data (p from replicated data only) or a level without the correction."""
    false_alarms = detections = 0
    for i in range(12):
        right = checks_of(data(100 + i), seed=i)
        wrong = checks_of(data(100 + i, scale=0.9), seed=i)
        assert [c.series for c in right] == ["all rows", "specular 15°", "specular 55°"]
        false_alarms += any(c.flagged for c in right)
        detections += right[0].flagged is False and wrong[0].flagged
        assert 0.5 < right[0].chi2_per_row < 2.0, right[0]
        assert wrong[0].chi2_per_row > 5.0, wrong[0]
    assert false_alarms <= 1, false_alarms
    assert detections >= 11, detections


def test_p_value_against_simulation():
    """The Rao-Blackwellised p equals the replicated-data simulation of BDA3 ch. 6 (y_rep =
    model + s sigma eps, p = Pr(T(y_rep) >= T(y))) within its Monte Carlo error (4 se, 40000
    replications: se <= 0.0025)."""
    d = data(7)
    rng = np.random.default_rng(3)
    model = d.reflectance[None, :] * (1 + 0.02 * rng.standard_normal((8, len(d))))
    s = np.full(8, 1.1)
    p = predictive_checks(d, model, s)[0].p_value
    reps = 5000
    t_obs = np.sum(((d.reflectance - model) / (1.1 * d.sigma)) ** 2, axis=1)
    t_rep = np.sum(rng.standard_normal((reps, 8, len(d))) ** 2, axis=2)
    sim = float(np.mean(t_rep >= t_obs[None, :]))
    assert abs(p - sim) < 4 * np.sqrt(0.25 / (reps * 8)), (p, sim)
    assert 0 < p < 1
    assert ALPHA / 3 < sidak_level(3) < ALPHA / 3 * 1.01 and abs(sidak_level(1) - ALPHA) < 1e-15


def test_draw_modes():
    """Two interference orders 150 nm apart with 3 nm width: two modes with their masses; one
    normal sample (any seed of 5) and a skewed log-normal: one mode."""
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(430, 3, 700), rng.normal(580, 3, 300)])
    modes = draw_modes(x)
    assert len(modes) == 2
    assert abs(modes[0][0] - 430) < 1 and abs(modes[1][1] - 0.3) < 1e-9
    for seed in range(5):
        assert len(draw_modes(np.random.default_rng(seed).normal(0, 1, 2000))) == 1
    assert len(draw_modes(np.random.default_rng(9).lognormal(0, 1, 2000))) == 1
    # a third small cluster under the 5 % floor is not a mode
    assert len(draw_modes(np.concatenate([x, rng.normal(800, 1, 20)]))) == 2


def test_bound_noise_and_mode_alerts():
    """A posterior piled at a uniform prior's end warns (one centred in it does not; one piled
    at the model's own limit says so with another code); a median 5 prior sd out conflicts,
    1.5 sd does not; a noise scale of 23 warns, 1.1 does not; MAP optima two orders apart
    with similar density warn, a far-worse second optimum does not."""
    rng = np.random.default_rng(1)
    priors = {"film_ior": Prior.make("film_ior", {"prior": "uniform", "low": 1.3, "high": 1.9})}
    piled = 1.3 + np.abs(rng.normal(0, 0.005, (500, 1)))
    alerts = bound_alerts(("film_ior",), piled, priors)
    assert [a.code for a in alerts] == ["PRIOR_BOUND"] and "lower bound 1.3" in alerts[0].message
    assert bound_alerts(("film_ior",), 1.6 + rng.normal(0, 0.05, (500, 1)), priors) == []
    spread = {"film_thickness_spread_nm": Prior.make("s", {"prior": "uniform", "low": 0.0, "high": 40.0})}
    alerts = bound_alerts(("film_thickness_spread_nm",), np.abs(rng.normal(0, 0.3, (500, 1))), spread)
    assert [a.code for a in alerts] == ["DOMAIN_BOUND"], alerts   # a spread of 0 is the model's limit
    normal = {"film_ior": Prior.make("film_ior", {"prior": "normal", "mean": 1.83, "sd": 0.02})}
    assert [a.code for a in conflict_alerts(("film_ior",), np.full((10, 1), 1.726), normal)] == ["PRIOR_CONFLICT"]
    assert conflict_alerts(("film_ior",), np.full((10, 1), 1.80), normal) == []   # 1.5 sd: no conflict
    assert conflict_alerts(("film_ior",), piled, priors) == []                     # uniform: PRIOR_BOUND's
    assert noise_alert(("noise_scale",), np.full((10, 1), 23.0))[0].code == "NOISE_SCALE"
    assert noise_alert(("noise_scale",), np.full((10, 1), 1.1)) == []
    draws = rng.normal(430, 2, (400, 1))
    near = [(np.array([430.0]), -10.0), (np.array([585.0]), -11.5)]
    assert [a.code for a in mode_alerts(("film_thickness_nm",), draws, near)] == ["THICKNESS_MODES"]
    far = [(np.array([430.0]), -10.0), (np.array([585.0]), -30.0)]
    assert mode_alerts(("film_thickness_nm",), draws, far) == []


def test_stop_reason_says_which_criterion():
    """The issue's "50.3 < 50": a capped run that passes the length test says so and names
    the stability test it failed; a converged run says ">" (the mutation: the old text)."""
    s = SamplerSettings(max_steps=5000, tau_multiple=50)
    tau = np.array([99.4])
    hist = [(4800, np.array([90.0])), (5000, tau)]
    r = stop_reason(5000, tau, hist, False, s)
    assert r.startswith("step cap 5000 reached") and "50.3 > 50 passed" in r and "not stable" in r
    assert "(not converged)" in r
    r = stop_reason(5000, np.array([400.0]), [(4800, np.array([400.0])), (5000, np.array([400.0]))], False, s)
    assert "N / max tau = 12.5 < 50" in r and "stable" in r
    r = stop_reason(5100, np.array([100.0]), [(5000, np.array([100.2])), (5100, np.array([100.0]))], True, s)
    assert r.startswith("converged: N / max tau = 51.0 > 50")


def test_study_warns_loudly(tmp_path, capsys, monkeypatch):
    """A study of data scaled by 0.8, fitted without a scale, at a step cap too short to
    converge: summary.json lists NOT_CONVERGED and PREDICTIVE_CHECK, residuals.png is
    written, and the CLI prints the warning block on stderr (exit 3 under --strict; its main
    called in this process, support.cli.cli_in_process: a child's imports cost ~4 CPU-s).
    With a free noise scale the common misfit moves to NOISE_SCALE. Mutation: the CLI's
    warning block left out of stderr fails it."""
    path = tmp_path / "d.csv"
    data(5, scale=0.8).write_csv(path)
    cfg = tmp_path / "fit.toml"
    cfg.write_text(FIT.format(seed=0, steps=100, extra="") + APPEARANCE)
    r = cli_in_process(capsys, monkeypatch, "fit", path, "--config", cfg, "--out", tmp_path / "s", "--quiet",
                       "--strict")
    assert r.returncode == 3, r.stderr   # --strict: a study with warnings fails (0 without it)
    summary = json.loads((tmp_path / "s" / "summary.json").read_text())
    codes = [w["code"] for w in summary["warnings"]]
    assert "NOT_CONVERGED" in codes and "PREDICTIVE_CHECK" in codes, codes
    assert (tmp_path / "s" / "residuals.png").is_file()
    assert summary["predictive_checks"]["series"][0]["flagged"]
    assert "warning(s)" in r.stderr and "[PREDICTIVE_CHECK]" in r.stderr and "[NOT_CONVERGED]" in r.stderr
    free = FitConfig.parse(tomllib.loads(FIT.format(
        seed=0, steps=300, extra='noise_scale = { prior = "lognormal", median = 1.0, sigma = 2.0 }') + APPEARANCE))
    summary = run_study(str(path), free, tmp_path / "s2", progress=False)
    assert "NOISE_SCALE" in [w["code"] for w in summary["warnings"]]


TWO_ORDERS = """
[truth]
film_thickness_nm = 400.0
[noise]
relative = 0.01
absolute = 0.0005
seed = 3
[[measurement]]
geometry = "specular"
angles_deg = [15]
wavelengths_nm = [450, 600]
"""


def two_orders_config(sampler: str) -> FitConfig:
    return FitConfig.parse(tomllib.loads(
        '[parameters]\nfilm_thickness_nm = { prior = "uniform", low = 300.0, high = 700.0 }\n'
        f"[model]\nthickness_nodes = 1\n[sampler]\n{sampler}\n" + APPEARANCE))


def test_nested_study_reports_evidence_and_both_orders(tmp_path):
    """Two interference orders of equal mass (400.6 and 593.0 nm, test_fit_nested.py): a
    ``[sampler] kind = "nested"`` study puts ln Z (with its error) in summary.json, warns
    THICKNESS_MODES from the draws, and builds material.json from the heavier mode alone
    (not the mean between the orders, ~500 nm, which no draw has). The emcee study of the same
    data, started in one mode, warns THICKNESS_MODES from its MAP starts' optima."""
    d = simulate(SimulationConfig.parse(tomllib.loads(TWO_ORDERS)))[0]
    nested = run_study(d, two_orders_config('kind = "nested"\nlive_points = 60\nseed = 1'), tmp_path / "n",
                       progress=False)
    assert nested["sampler"] == "nested" and np.isfinite(nested["log_evidence"])
    assert 0 < nested["log_evidence_error"] < 1
    modes = [w for w in nested["warnings"] if w["code"] == "THICKNESS_MODES"]
    assert modes and "2 separate modes" in modes[0]["message"], nested["warnings"]
    d_mat = nested["posterior_mean"]["film_thickness_nm"]
    assert min(abs(d_mat - 400.6), abs(d_mat - 593.0)) < 10, d_mat
    assert "ESS (Kish)" in (tmp_path / "n" / "parameters.md").read_text()
    emcee = run_study(d, two_orders_config("walkers = 8\nmax_steps = 200\nmap_starts = 8\nseed = 2"),
                      tmp_path / "e", progress=False)
    assert "THICKNESS_MODES" in [w["code"] for w in emcee["warnings"]], emcee["warnings"]


def test_sampler_kind_is_checked():
    import pytest

    with pytest.raises(ValueError, match="kind must be one of emcee, nested"):
        two_orders_config('kind = "tempering"')
    with pytest.raises(ValueError, match="live_points"):
        two_orders_config('kind = "nested"\nlive_points = 1')


def test_render_labels_carry_the_rendered_values():
    """Each render's caption shows the thickness it was rendered with and the other free
    parameters' values (the mutation: a fixed thickness in every label)."""
    from bsdflab.fit.config import ModelSettings
    from bsdflab.fit.parameters import ALL
    from bsdflab.fit.study import render_label

    v = np.array([ALL[n].default for n in ALL_NAMES])
    v[ALL_NAMES.index("film_thickness_nm")] = 437.25
    v[ALL_NAMES.index("roughness")] = 0.123
    assert render_label("draw 2", v, ModelSettings(kind="full"), ("roughness", "noise_scale")) == \
        "draw 2: d = 437.2 nm, α 0.123"
    v[ALL_NAMES.index("platelet_nm")] = 91.0
    assert render_label("mean", v, ModelSettings(kind="full", film="stack", platelets=4), ()) == "mean: 4 x 91.0 nm"
    assert render_label("mean", v, ModelSettings(kind="full", film="none"), ()) == "mean"
