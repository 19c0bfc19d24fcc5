"""Co-refinement with the full model of a [structure] (bsdflab.fit.full_stack_posterior):
two gonio datasets, each through its own instrument (scale 0.9 at 30 deg incidence, 1.2 at
60 deg), share the structure's roughness. The data are made by an independent path: the
example's Layered dict written by hand (examples/fit/structure_full/make_data.py, not
FullStructure), a direct ``bsdflab.solvers.solve`` of it (not the fit's forward model nor
its emulator), the scales and 2 % Gaussian noise applied in numpy. Fitted jointly: every
truth inside its 99.7 % interval, and the shared roughness's interval narrower than from
either dataset alone (each dataset's scale is degenerate with the level of pi f, so each
informs the roughness through the shape of its own rows only)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import tomllib

from bsdflab.bsdfs import from_dict
from bsdflab.fit import run_sampler
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.full_stack_config import FullStackConfig
from bsdflab.fit.full_stack_posterior import FullStackPosterior
from bsdflab.solvers import solve

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "fit" / "structure_full"
_spec = importlib.util.spec_from_file_location("make_structure_full_data", EXAMPLE / "make_data.py")
make_data = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(make_data)

TRUTH = {"roughness": 0.12, "sigma_s": 0.4, "base_albedo": 0.35}
SCALES = {"near": 0.9, "far": 1.2}
# (theta_i, theta_o, phi) per dataset: one goniometer arm position each, the gloss lobe's
# flanks included (they carry the roughness)
DESIGN = {
    "near": [[30, 30, 0], [30, 20, 0], [30, 40, 0], [30, 50, 0], [30, 0, 0], [30, 35, 20]],
    "far": [[60, 60, 0], [60, 50, 0], [60, 70, 0], [60, 40, 0], [60, 60, 15]],
}
RELATIVE = 0.02

CONFIG = """
[model]
kind = "full"
emulator_nodes = 5
emulator_checks = 2
[structure]
exterior = "air"
substrate = "keratin"
[[structure.layers]]
name = "film"
material = "guanine"
thickness_nm = 400.0
[structure.interface]
roughness = 0.1
distribution = "ggx"
[structure.slab]
thickness_um = 4.0
sigma_a = "eumelanin"
pigment_absorption = 0.4
sigma_s = 0.4
hg_g = 0.6
[structure.base]
albedo = 0.35
[parameters]
roughness = { prior = "lognormal", median = 0.1, sigma = 0.2 }
[sampler]
walkers = 8
max_steps = 1500
check_every = 100
map_starts = 2
seed = 7
"""


def datasets() -> dict[str, Dataset]:
    """The two datasets at 550 nm: scale * pi f of a direct solve of the hand-written dict,
    2 % Gaussian noise (seeded), sigma = 2 % of the noiseless value."""
    sol = solve(from_dict(make_data.truth_model(TRUTH)), wavelengths=[550.0])
    rng = np.random.default_rng(11)
    out = {}
    for name, triples in DESIGN.items():
        ds = make_data.design(triples, [550.0])
        det, src = make_data.directions(ds)
        y = SCALES[name] * np.pi * sol.eval(det, src)[:, 0] / src[:, 2]
        sigma = RELATIVE * y
        n = len(y)
        out[name] = Dataset(
            np.full(n, GEOMETRIES.index("brdf")),
            ds.angle_deg,
            ds.angle_out_deg,
            ds.wavelength_nm,
            y + sigma * rng.standard_normal(n),
            sigma,
            phi_deg=ds.phi_deg,
        )
    return out


def config_of(names) -> FullStackConfig:
    d = tomllib.loads(CONFIG)
    scale = {"prior": "uniform", "low": 0.5, "high": 1.5}
    d["dataset"] = [{"name": n, "data": f"{n}.csv", "instrument": {"scale": scale}} for n in names]
    return FullStackConfig.parse(d)


def fit(post: FullStackPosterior):
    run = run_sampler(post, post.stack.sampler, progress=False)
    lo, hi = np.quantile(run.draws(), [0.0015, 0.9985], axis=0)
    return run, dict(zip(run.names, zip(lo, hi)))


def alone(post: FullStackPosterior, name: str) -> FullStackPosterior:
    """Dataset ``name`` alone, through the joint fit's emulator (no second grid of solves):
    the other dataset's sigma raised to 1e9 makes its likelihood flat (chi^2 terms < 1e-15),
    the one-dataset likelihood times a constant; the other scale then follows its prior,
    independent of the roughness, whose marginal is the one-dataset posterior's."""
    ds = post.dataset
    own = np.array([str(s).split("/")[0] == name for s in ds.series])
    assert own.sum() == len(DESIGN[name])
    return post.with_data(ds.with_reflectance(ds.reflectance, np.where(own, ds.sigma, 1e9)))


def test_corefinement_shares_the_structure():
    data = datasets()
    config = config_of(("near", "far"))
    post = FullStackPosterior([data[n] for n in ("near", "far")], config)
    run, joint = fit(post)
    assert post.model.max_error_sigma < 0.3, post.model.max_error_sigma  # the emulator is not the error
    truth = {"roughness": TRUTH["roughness"], "near.scale": SCALES["near"], "far.scale": SCALES["far"]}
    assert set(run.names) == set(truth), run.names
    for name, value in truth.items():
        lo, hi = joint[name]
        assert lo < value < hi, (name, lo, hi, value)
    widths = {}
    for name in ("near", "far"):
        _, one = fit(alone(post, name))
        lo, hi = one["roughness"]
        assert lo < TRUTH["roughness"] < hi, (name, lo, hi)
        widths[name] = hi - lo
    joint_width = joint["roughness"][1] - joint["roughness"][0]
    assert joint_width < min(widths.values()), (joint_width, widths)
