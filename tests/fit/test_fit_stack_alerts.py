"""The structure study says loudly when it does not fit (bsdflab.fit.stack_study with
bsdflab.fit.checks and bsdflab.fit.alerts): data made by tmm (tests/support/stack_data.py,
not the fit's forward model) through an instrument of scale 0.8, fitted

- with scale free: the right model; the predictive checks (family-wise alpha 0.01, Sidak
  over "all rows" + 3 angles) pass and the study raises no warning at all;
- with scale fixed at 1 (the instrument left out): every row is 20 % high against 1 % noise,
  so the checks fail (PREDICTIVE_CHECK), the mutation the first case must not hide;
- with a 1-layer structure for 2-layer data (the cytoplasm gap left out): PREDICTIVE_CHECK.

noise_scale is fixed at 1 (the stated sigmas are the truth), so no free scale absorbs the
misfit. Seeds fixed; each study is a few thousand short forward calls."""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from bsdflab.fit.config import OutputSettings
from bsdflab.fit.stack_config import StackConfig
from bsdflab.fit.stack_study import run_stack_study
from support.stack_data import synthetic, two_layer_config

TRUTH = dict(film_thickness_nm=900.0, gap_thickness_nm=150.0, film_ior=1.85, substrate_ior=1.54, scale=0.8,
             background=0.0, angle_offset_deg=0.0, bandwidth_nm=0.0)
SCALE_PRIOR = {"scale": {"prior": "uniform", "low": 0.5, "high": 1.5}}


# the cap leaves room for the stop rule's 1 % tau stability: with the DE moves tau is ~19 and
# its estimate still wanders 1-2 % between checks at N / tau ~150 (converged at 3700 steps)
def config(instrument: dict, one_layer: bool = False, max_steps: int = 6000) -> StackConfig:
    c = two_layer_config(instrument, walkers=16, max_steps=max_steps)
    c["sampler"].update(check_every=100, map_starts=2)
    if one_layer:
        c["structure"]["layers"] = c["structure"]["layers"][:1]
        del c["parameters"]["gap_thickness_nm"]
    return StackConfig.parse(c)


@pytest.fixture(scope="module")
def data():
    return synthetic(TRUTH, [15, 40, 65], np.arange(400.0, 701.0, 15.0), seed=3)


def codes(summary: dict) -> list[str]:
    return [w["code"] for w in summary["warnings"]]


def test_right_model_is_quiet(data, tmp_path):
    s = run_stack_study(config(SCALE_PRIOR), tmp_path / "right", data, progress=False)
    assert s["converged"], s["stop_reason"]
    assert s["warnings"] == [], s["warnings"]
    checks = s["predictive_checks"]["series"]
    assert [c["series"] for c in checks] == ["all rows", "specular 15°", "specular 40°", "specular 65°"]
    assert not any(c["flagged"] for c in checks)
    assert (tmp_path / "right" / "residuals.png").is_file()
    assert json.loads((tmp_path / "right" / "summary.json").read_text())["warnings"] == []


@pytest.mark.parametrize("instrument, one_layer", [({"scale": 1.0}, False), (SCALE_PRIOR, True)],
                         ids=["scale left out", "gap left out"])
def test_wrong_model_warns(data, tmp_path, instrument, one_layer):
    """No convergence needed: the misfit is in every draw (a short run; NOT_CONVERGED may
    join). The warnings come from summary.json's checks, not the figures: [output] figures =
    false (test_right_model_is_quiet keeps them and reads residuals.png). Mutation: the
    PREDICTIVE_CHECK alerts dropped from stack_study's fit_alerts fails both cases; the
    warning pointing at a residuals.png the study did not write fails the last check."""
    cfg = replace(config(instrument, one_layer, max_steps=300), output=OutputSettings(figures=False))
    s = run_stack_study(cfg, tmp_path / "wrong", data, progress=False)
    assert "PREDICTIVE_CHECK" in codes(s), s["warnings"]
    (message,) = [w["message"] for w in s["warnings"] if w["code"] == "PREDICTIVE_CHECK"]
    assert "summary.json" in message and "residuals.png" not in message
    assert not (tmp_path / "wrong" / "residuals.png").exists()
    assert s["predictive_checks"]["series"][0]["flagged"]          # "all rows" fails


def test_the_wide_example_stack_config_binds_to_its_import():
    """docs/fit.md's worked example: examples/fit/wide/stack.toml loads and binds to the 852
    imported rows of examples/fit/wide/angles.csv, and its posterior prefers the data's truth
    (film 430 nm, index 1.83) to a thickness 20 nm off by ln p > 100 (mutations caught: rows
    lost in the import; a film thickness that does not reach the forward model)."""
    from bsdflab.fit.readers import import_files, load_spec
    from bsdflab.fit.stack_posterior import StackPosterior

    path = "examples/fit/wide/angles.csv"
    ds, _ = import_files([path], load_spec(path + ".toml"))
    post = StackPosterior([ds], StackConfig.load("examples/fit/wide/stack.toml"))
    assert len(post.dataset) == 852
    assert post.free == ("film_thickness_nm", "film_ior", "substrate_ior", "noise_scale", "scale")
    truth, off = [430.0, 1.83, 1.5515, 1.8, 0.99], [450.0, 1.83, 1.5515, 1.8, 0.99]
    lp = post(np.array([truth, off]))
    assert np.all(np.isfinite(lp)) and lp[0] > lp[1] + 100, lp
