"""The shipped example configs (examples/fit/: the smooth model, the full model, nested
sampling of two interference orders) load, match their data, and their data regenerate from
their truth.toml (so the README's ``bsdflab fit simulate`` command is the one that made them)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bsdflab.fit import FitConfig, LogPosterior, SimulationConfig, read_csv, simulate
from bsdflab.fit.parameters import ALL_NAMES

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "fit"
FOLDERS = [EXAMPLES, EXAMPLES / "full", EXAMPLES / "orders"]


def test_every_example_folder_is_listed():
    """A new example folder must join FOLDERS (the mutation: an untested config)."""
    found = sorted(p.parent for p in EXAMPLES.rglob("fit.toml"))
    assert found == sorted(FOLDERS)


@pytest.mark.parametrize("folder", FOLDERS, ids=lambda p: p.name)
def test_example_loads_and_regenerates(folder):
    """fit.toml and truth.toml parse; both name the same model; data.csv equals a fresh
    simulation of truth.toml to the file's 10 printed digits (rtol 1e-9 + the sigma's 6)."""
    config = FitConfig.load(folder / "fit.toml")
    truth = SimulationConfig.load(folder / "truth.toml")
    assert (config.model.kind, config.model.film) == (truth.model.kind, truth.model.film)
    data = read_csv(folder / "data.csv")
    fresh, _ = simulate(truth)
    assert len(fresh) == len(data)
    np.testing.assert_allclose(data.reflectance, fresh.reflectance, rtol=1e-9, atol=0)
    np.testing.assert_allclose(data.sigma, fresh.sigma, rtol=1e-5, atol=0)
    if config.model.kind == "smooth":   # the full model's emulator is minutes of solves: built by the study
        post = LogPosterior(data, config)
        at_truth = [truth.truth.get(n, np.nan) if n != "noise_scale" else 1.0 for n in config.free]
        assert np.isfinite(post(np.array(at_truth))[0])
    assert set(config.free) <= set(ALL_NAMES)
