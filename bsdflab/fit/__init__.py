"""MCMC parameter-uncertainty studies: reflectance data -> posterior -> appearance.

    from bsdflab import fit
    data = fit.read_csv("examples/fit/data.csv")
    config = fit.FitConfig.load("examples/fit/fit.toml")
    fit.run_study(data, config, "study/")

Modules: parameters (names, units, defaults), forward (the smooth C++ forward model),
full_forward (the full model: the rendered Layered model through the adding-doubling
solver) and emulator (its Chebyshev emulator), data (CSV), priors and config (TOML),
posterior, sampling (MAP + emcee), nested (dynesty: multi-modal posteriors, evidence),
diagnostics (ArviZ), appearance (colour posterior), material (model dict), study (the
folder), simulate. See docs/fit.md.
"""
from bsdflab.fit.config import FitConfig, SimulationConfig
from bsdflab.fit.data import GEOMETRIES, MODEL_RANGE_NM, Dataset, parse_csv, read_csv
from bsdflab.fit.forward import ForwardModel, default_theta
from bsdflab.fit.nested import NestedResult, run_nested
from bsdflab.fit.parameters import ALL_NAMES, FORWARD_NAMES, PARAMETERS
from bsdflab.fit.posterior import LogPosterior
from bsdflab.fit.sampling import run_sampler
from bsdflab.fit.simulate import simulate
from bsdflab.fit.study import run_study

__all__ = ["ALL_NAMES", "Dataset", "FORWARD_NAMES", "FitConfig", "ForwardModel", "GEOMETRIES", "LogPosterior",
           "MODEL_RANGE_NM", "NestedResult", "PARAMETERS", "SimulationConfig", "default_theta", "parse_csv",
           "read_csv", "run_nested", "run_sampler", "run_study", "simulate"]
