"""MCMC parameter-uncertainty studies: reflectance data -> posterior -> appearance.

    from bsdflab import fit
    data = fit.read_csv("examples/fit/data.csv")
    config = fit.FitConfig.load("examples/fit/fit.toml")
    fit.run_study(data, config, "study/")

Modules: parameters (names, units, defaults), forward (the C++ forward model), data (CSV),
priors and config (TOML), posterior, sampling (MAP + emcee), diagnostics (ArviZ),
appearance (colour posterior), material (model dict), study (the folder), simulate.
The layered part is restricted to non-scattering slabs (see docs/fit.md).
"""
from .config import FitConfig, SimulationConfig
from .data import GEOMETRIES, MODEL_RANGE_NM, Dataset, parse_csv, read_csv
from .forward import ForwardModel, default_theta
from .parameters import ALL_NAMES, FORWARD_NAMES, PARAMETERS
from .posterior import LogPosterior
from .sampling import run_sampler
from .simulate import simulate
from .study import run_study

__all__ = ["ALL_NAMES", "Dataset", "FORWARD_NAMES", "FitConfig", "ForwardModel", "GEOMETRIES", "LogPosterior",
           "MODEL_RANGE_NM", "PARAMETERS", "SimulationConfig", "default_theta", "parse_csv", "read_csv",
           "run_sampler", "run_study", "simulate"]
