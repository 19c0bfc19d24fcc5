"""Fitting: bsdflab's C++ forward model against the same model with colour-science's
``thin_film_tmm`` (vectorised numpy) or ``tmm`` (pure Python) as the film part, in one run.

Workload: the specular rows of the shipped synthetic example (examples/fit/data.csv:
4 angles x 36 wavelengths = 144 rows), thickness spread by 8 Gauss-Hermite nodes. Each
peer computes exactly the same observables (checked to 1e-9 here) -- only the film part
differs. Prints forward-model evaluations per second (one evaluation = one parameter set,
all rows) and effective samples per second of the same emcee study (same data, priors,
start and seed) with each forward model, and the ratios. bsdflab runs on all threads and
on one (BSDFLAB_THREADS=1); the peers on one.

    python3 bench/bench_fit.py
Profile:  python3 -m cProfile -s cumtime bench/bench_fit.py | head -40

    python3 bench/bench_fit.py --stack      # only the third part

Second part: the full model (the rendered Layered model through the adding-doubling solver,
docs/fit.md) against the smooth model on the same gonio brdf rows: forward evaluations/s of
the smooth C++ model, the full model's emulator and its direct solves, the emulator's build
time, and ESS/s of an emcee run with each (the direct-solve ESS/s from its evaluation rate).

Third part: issue 30's speed case, a structure + instrument fit of 852 specular rows to
convergence, beside the forward cost of today's smooth model (structure_with_instrument).
"""
from __future__ import annotations

import os
import time
import warnings

import emcee
import numpy as np
import tmm
import tomllib
from colour.phenomena import thin_film_tmm

from bsdflab.fit import GEOMETRIES, FitConfig, ForwardModel, LogPosterior, read_csv
from bsdflab.fit.parameters import FORWARD_NAMES

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "examples", "fit", "data.csv")
NODES = 8
CONFIG = f"""
[parameters]
film_thickness_nm = {{ prior = "uniform", low = 300.0, high = 600.0 }}
film_thickness_spread_nm = {{ prior = "uniform", low = 0.0, high = 40.0 }}
film_ior = {{ prior = "normal", mean = 1.83, sd = 0.05 }}
[model]
thickness_nodes = {NODES}
[sampler]
walkers = 8
"""
STEPS = 60
COL = {n: i for i, n in enumerate(FORWARD_NAMES)}


class PeerForwardModel:
    """The specular part of bsdflab.fit's forward model with a third-party film code."""

    def __init__(self, dataset, nodes: int, film: str):
        if np.any(dataset.geometry != GEOMETRIES.index("specular")):
            raise ValueError("the peer implements specular rows only")
        self.ds, self.film = dataset, film
        self.wl, self.wl_index = np.unique(dataset.wavelength_nm, return_inverse=True)
        self.angles, self.angle_index = np.unique(dataset.angle_deg, return_inverse=True)
        x, w = np.polynomial.hermite.hermgauss(nodes)
        self.x, self.w = x, w / w.sum()

    def evaluate(self, theta):
        theta = np.atleast_2d(theta)
        return np.array([self._one(t) for t in theta])

    def _one(self, t):
        d = np.maximum(0.0, t[COL["film_thickness_nm"]] + np.sqrt(2) * t[COL["film_thickness_spread_nm"]] * self.x)
        if t[COL["film_thickness_spread_nm"]] == 0:
            d, w = d[:1], np.ones(1)
        else:
            w = self.w
        n_e, n_s = t[COL["exterior_ior"]], t[COL["substrate_ior"]]
        R = np.empty((len(self.wl), len(self.angles)))
        for j, lam in enumerate(self.wl):
            n_f = t[COL["film_ior"]] + t[COL["film_cauchy_b"]] / lam**2
            if self.film == "colour":
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    r, _ = thin_film_tmm([n_e, n_f, n_s], d, np.array([lam]), self.angles)
                R[j] = r[0].mean(axis=-1) @ w          # (angles, nodes, pol) -> (angles,)
            else:
                for a, ang in enumerate(self.angles):
                    R[j, a] = sum(wk * tmm.unpolarized_RT([n_e, n_f, n_s], [np.inf, dk, np.inf],
                                                          np.radians(ang), lam)["R"] for dk, wk in zip(d, w))
        return R[self.wl_index, self.angle_index]


def evals_per_second(model, theta, min_seconds=1.5):
    n, start = 0, time.perf_counter()
    while True:
        model.evaluate(theta)
        n += len(theta)
        elapsed = time.perf_counter() - start
        if elapsed > min_seconds:
            return n / elapsed


class FullVectors:
    """A forward model of the smooth model's 10 columns behind LogPosterior's interface (full
    parameter vectors in ALL_NAMES order, whose first columns are FORWARD_NAMES)."""

    def __init__(self, model):
        self.model = model

    def evaluate(self, full):
        return self.model.evaluate(np.atleast_2d(full)[:, :len(FORWARD_NAMES)])


def study(logpost, model, p0, seed):
    logpost.model = FullVectors(model)
    sampler = emcee.EnsembleSampler(len(p0), logpost.ndim, logpost, vectorize=True)
    sampler.random_state = np.random.RandomState(seed).get_state()
    start = time.perf_counter()
    sampler.run_mcmc(p0, STEPS, progress=False)
    seconds = time.perf_counter() - start
    chain = sampler.get_chain()
    tau = emcee.autocorr.integrated_time(chain, tol=0)
    return chain, float(np.min(STEPS * len(p0) / tau)), seconds


def main():
    ds = read_csv(DATA)
    keep = ds.geometry == GEOMETRIES.index("specular")
    ds = ds.__class__(*(getattr(ds, f)[keep] for f in ("geometry", "angle_deg", "angle_out_deg", "wavelength_nm",
                                                         "reflectance", "sigma")))
    config = FitConfig.parse(tomllib.loads(CONFIG))
    ours = ForwardModel(ds, NODES)
    colour_peer, tmm_peer = PeerForwardModel(ds, NODES, "colour"), PeerForwardModel(ds, NODES, "tmm")
    logpost = LogPosterior(ds, config)
    rng = np.random.default_rng(0)
    sets = logpost.full(logpost.sample_prior(32, rng))[:, :len(FORWARD_NAMES)]
    ref = ours.evaluate(sets[:3])
    for peer in (colour_peer, tmm_peer):
        err = np.max(np.abs(peer.evaluate(sets[:3]) - ref))
        assert err < 1e-9, f"peer disagrees by {err}"
    print(f"load: {os.getloadavg()[0]:.1f} (1-min average; the machine may be shared)")
    print(f"forward model, {ds.geometry.size} specular rows, {NODES} thickness nodes, per parameter set:")
    rates = {}
    rates["bsdflab"] = evals_per_second(ours, sets)
    os.environ["BSDFLAB_THREADS"] = "1"
    rates["bsdflab 1 thread"] = evals_per_second(ours, sets)
    del os.environ["BSDFLAB_THREADS"]
    rates["colour thin_film_tmm"] = evals_per_second(colour_peer, sets[:4])
    rates["tmm"] = evals_per_second(tmm_peer, sets[:1], min_seconds=3.0)
    for name, r in rates.items():
        print(f"  {name:<22} {r:12.1f} evaluations/s")
    print(f"  ratio bsdflab / colour  {rates['bsdflab'] / rates['colour thin_film_tmm']:8.1f}x "
          f"(1 thread: {rates['bsdflab 1 thread'] / rates['colour thin_film_tmm']:.1f}x)")
    print(f"  ratio bsdflab / tmm     {rates['bsdflab'] / rates['tmm']:8.1f}x "
          f"(1 thread: {rates['bsdflab 1 thread'] / rates['tmm']:.1f}x)")

    centre = np.array([430.0, 12.0, 1.83])
    p0 = centre + 1e-3 * np.array([1.0, 1.0, 1e-3]) * rng.standard_normal((config.sampler.walkers, 3))
    print(f"emcee study: {config.sampler.walkers} walkers x {STEPS} steps, same start and seed")
    c_ours, ess_ours, t_ours = study(logpost, ours, p0, 1)
    c_peer, ess_peer, t_peer = study(logpost, colour_peer, p0, 1)
    same = np.max(np.abs(c_ours - c_peer))
    print(f"  chains identical to {same:.1e} (so the ESS is the same; ESS/s differs by time)")
    print(f"  bsdflab  {t_ours:8.2f} s  ESS {ess_ours:6.1f}  {ess_ours / t_ours:10.2f} ESS/s")
    print(f"  colour   {t_peer:8.2f} s  ESS {ess_peer:6.1f}  {ess_peer / t_peer:10.2f} ESS/s")
    print(f"  ESS/s ratio bsdflab / colour-film study: {(ess_ours / t_ours) / (ess_peer / t_peer):.1f}x "
          f"(tmm-film study, from its evaluation rate: "
          f"~{(ess_ours / t_ours) / (ess_peer / t_peer) * rates['colour thin_film_tmm'] / rates['tmm']:.0f}x)")


# -- the full model (adding-doubling solver) against the smooth one, same gonio rows --------
GONIO_PAIRS = [(30, 20, 0), (30, 40, 0), (30, 60, 0), (30, 0, 0), (30, 45, 90), (30, 60, 180), (60, 40, 0),
               (60, 75, 0)]
GONIO_WAVELENGTHS = (450.0, 550.0, 650.0)
FULL_STEPS = 400
SMOOTH_GONIO = """
[parameters]
film_thickness_nm = { prior = "normal", mean = 400.0, sd = 10.0 }
base_albedo = { prior = "uniform", low = 0.01, high = 0.6 }
[sampler]
walkers = 8
"""
FULL_GONIO = """
[parameters]
roughness = { prior = "lognormal", median = 0.08, sigma = 0.25 }
sigma_s = { prior = "uniform", low = 0.05, high = 0.5 }
[model]
kind = "full"
emulator_nodes = 5
emulator_checks = 2
[sampler]
walkers = 8
"""


def gonio_dataset():
    from bsdflab.fit.data import Dataset

    rows = np.array([(*p, wl) for wl in GONIO_WAVELENGTHS for p in GONIO_PAIRS], float)
    n = len(rows)
    return Dataset(np.full(n, GEOMETRIES.index("brdf")), rows[:, 0], rows[:, 1], rows[:, 3], np.zeros(n),
                   np.ones(n), phi_deg=rows[:, 2])


def timed_emcee(logpost, p0, seed=1):
    sampler = emcee.EnsembleSampler(len(p0), logpost.ndim, logpost, vectorize=True)
    sampler.random_state = np.random.RandomState(seed).get_state()
    start = time.perf_counter()
    sampler.run_mcmc(p0, FULL_STEPS, progress=False)
    seconds = time.perf_counter() - start
    tau = emcee.autocorr.integrated_time(sampler.get_chain(), tol=0)
    return float(np.min(FULL_STEPS * len(p0) / tau)), seconds


def full_vs_smooth():
    from bsdflab.fit.full_forward import SolverForwardModel

    ds = gonio_dataset()
    print(f"full model (adding-doubling) vs smooth model: {len(ds)} brdf rows "
          f"({len(GONIO_PAIRS)} pairs x {len(GONIO_WAVELENGTHS)} wavelengths), 2 free parameters each")
    smooth = LogPosterior(ds, FitConfig.parse(tomllib.loads(SMOOTH_GONIO)))
    start = time.perf_counter()
    full = LogPosterior(ds, FitConfig.parse(tomllib.loads(FULL_GONIO)))
    build = time.perf_counter() - start
    emu = full.model
    direct = SolverForwardModel(ds, full.config.model)
    rng = np.random.default_rng(3)
    xs, xf = smooth.sample_prior(32, rng), full.sample_prior(32, rng)
    rates = {"smooth (C++ closed form)": evals_per_second(smooth.model, smooth.full(xs)),
             "full, emulated": evals_per_second(emu, full.full(xf)),
             "full, direct solves": evals_per_second(direct, full.full(xf[:2]), min_seconds=3.0)}
    for name, r in rates.items():
        print(f"  {name:<26} {r:12.2f} evaluations/s")
    print(f"  emulator build: {emu.solves} solves in {build:.1f} s; measured error {emu.max_relative_error:.1e} "
          "relative")
    print(f"  ratio smooth / full direct {rates['smooth (C++ closed form)'] / rates['full, direct solves']:10.0f}x; "
          f"smooth / full emulated {rates['smooth (C++ closed form)'] / rates['full, emulated']:.1f}x")
    # data: the full model at its defaults + 1 % noise (the smooth fit is misspecified: timing only)
    y = direct.evaluate(full.full(np.array([[0.1, 0.3]])))[0]
    data = ds.with_reflectance(y * (1 + 0.01 * rng.standard_normal(len(y))), 0.01 * y)
    smooth, full = smooth.with_data(data), full.with_data(data)
    ess_s, t_s = timed_emcee(smooth, np.array([400.0, 0.05]) + 1e-3 * rng.standard_normal((8, 2)))
    ess_f, t_f = timed_emcee(full, np.array([0.1, 0.3]) + 1e-4 * rng.standard_normal((8, 2)))
    per_eval = ess_f / (FULL_STEPS * 8)
    print(f"  emcee, 8 walkers x {FULL_STEPS} steps:")
    print(f"    smooth         {t_s:8.2f} s  ESS {ess_s:6.1f}  {ess_s / t_s:10.2f} ESS/s")
    print(f"    full emulated  {t_f:8.2f} s  ESS {ess_f:6.1f}  {ess_f / t_f:10.2f} ESS/s "
          f"({ess_f / (t_f + build):.2f} ESS/s with the build)")
    print(f"    full direct    (from its rate) {per_eval * rates['full, direct solves']:10.4f} ESS/s")
    print(f"  ESS/s ratio smooth / full emulated: {(ess_s / t_s) / (ess_f / t_f):.1f}x (with the build: "
          f"{(ess_s / t_s) / (ess_f / (t_f + build)):.0f}x); smooth / full direct: "
          f"{(ess_s / t_s) / (per_eval * rates['full, direct solves']):.0f}x")


STACK_TRUTH = {"film_thickness_nm": 420.0, "gap_thickness_nm": 160.0, "film_ior": 1.82, "substrate_ior": 1.54,
               "scale": 0.85, "background": 0.008, "angle_offset_deg": 1.2, "bandwidth_nm": 12.0, "noise_scale": 1.0}
STACK_CONFIG = {
    "structure": {"exterior": "air", "substrate": {"cauchy": [1.532, 5890.0]}, "layers": [
        {"name": "film", "material": {"n": 1.83}, "thickness_nm": 400.0},
        {"name": "gap", "material": "cytoplasm", "thickness_nm": 150.0}]},
    "instrument": {"scale": {"prior": "uniform", "low": 0.5, "high": 1.5},
                   "background": {"prior": "normal", "mean": 0.0, "sd": 0.02},
                   "angle_offset_deg": {"prior": "normal", "mean": 0.0, "sd": 2.0},
                   "bandwidth_nm": {"prior": "uniform", "low": 0.0, "high": 30.0}},
    "parameters": {"film_thickness_nm": {"prior": "uniform", "low": 350.0, "high": 500.0},
                   "gap_thickness_nm": {"prior": "uniform", "low": 80.0, "high": 250.0},
                   "film_ior": {"prior": "normal", "mean": 1.83, "sd": 0.05},
                   "substrate_ior": {"prior": "normal", "mean": 1.532, "sd": 0.03},
                   "noise_scale": {"prior": "lognormal", "median": 1.0, "sigma": 0.5}},
    "sampler": {"walkers": 24, "max_steps": 20000, "tau_multiple": 50, "check_every": 200, "seed": 0},
}


def structure_with_instrument():
    """Issue 30's speed case: 12 angles (15-70 deg) x 71 wavelengths (350-700 nm) = 852
    specular rows of air | film | cytoplasm gap | keratin-like substrate through scale,
    background, angle offset and a slit (9 free parameters with noise_scale), run by the
    study's sampler to its stop rule (N > 50 tau, tau stable). Beside it, in the same run,
    the forward cost per parameter set of today's smooth model (one film) on the same rows
    and of the stack without and with the slit."""
    from bsdflab.fit import Dataset, default_theta, run_sampler
    from bsdflab.fit.stack_config import StackConfig
    from bsdflab.fit.stack_posterior import StackPosterior

    angles, wls = np.linspace(15.0, 70.0, 12), np.arange(350.0, 701.0, 5.0)
    n = len(angles) * len(wls)
    rows = Dataset(np.zeros(n, int), np.repeat(angles, len(wls)), np.full(n, np.nan), np.tile(wls, len(angles)),
                   np.zeros(n), np.ones(n))
    config = StackConfig.parse(STACK_CONFIG)
    truth_post = StackPosterior([rows], config)
    truth = np.array([[STACK_TRUTH[k] for k in truth_post.free]])
    y = truth_post.predict(truth)[0]
    sigma = np.sqrt(0.002**2 + (0.01 * y) ** 2)
    data = rows.with_reflectance(y + sigma * np.random.default_rng(3).standard_normal(n), sigma)
    post = StackPosterior([data], config)
    print(f"\nstructure + instrument: {n} specular rows (12 angles x {len(wls)} wavelengths), "
          f"{post.ndim} free parameters; load {os.getloadavg()[0]:.1f}")
    smooth = ForwardModel(data)
    sets = 16
    rates = {"smooth model (1 film), today": evals_per_second(smooth, np.repeat(default_theta()[None], sets, 0))}

    class Stack:
        def __init__(self, bandwidth):
            x = np.repeat(truth, sets, 0)
            x[:, post.free.index("bandwidth_nm")] = bandwidth
            self.x = x

        def evaluate(self, theta):
            return post.predict(self.x)
    rates["stack, no slit"] = evals_per_second(Stack(0.0), np.zeros((sets, 1)))
    rates["stack + slit, shared grid"] = evals_per_second(Stack(12.0), np.zeros((sets, 1)))
    grid_step = post.models[0]._step
    post.models[0]._step = None  # force the per-row Gauss-Hermite slit for comparison
    rates["stack + slit, 7 GH nodes"] = evals_per_second(Stack(12.0), np.zeros((sets, 1)))
    post.models[0]._step = grid_step
    base = rates["smooth model (1 film), today"]
    for name, r in rates.items():
        print(f"  {name:<30} {r:10.1f} evaluations/s  ({base / r:5.1f}x the smooth model's cost)")
    cpu = time.process_time()
    run = run_sampler(post, config.sampler, progress=False)
    cpu = time.process_time() - cpu
    lo, hi = np.quantile(run.draws(), [0.0015, 0.9985], axis=0)
    inside = int(np.sum((lo < truth[0]) & (truth[0] < hi)))
    print(f"  sampler: {run.seconds:.1f} s wall ({run.seconds / 60:.2f} min), {run.steps} steps x "
          f"{config.sampler.walkers} walkers, max tau {np.max(run.tau):.1f}, {run.evaluations} evaluations; "
          f"{cpu:.1f} CPU-s (2 cores x 5 min = 600 CPU-s)")
    print(f"  stop: {run.stop_reason}")
    print(f"  truth inside the 99.7 % interval for {inside} of {post.ndim} parameters")


if __name__ == "__main__":
    import sys

    if "--stack" not in sys.argv:
        main()
        full_vs_smooth()
    structure_with_instrument()
