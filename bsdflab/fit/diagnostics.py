"""Posterior summaries and diagnostics; the run as ArviZ InferenceData (netCDF).

ESS: two estimates per parameter. ``ess_tau`` is emcee's, (N - burn) x walkers / tau from the
ensemble's integrated autocorrelation time. ``ess_bulk`` / ``ess_tail`` are ArviZ's
rank-normalised estimates treating each walker as a chain. R-hat is ArviZ's rank-normalised
split R-hat over the walkers; walkers of ONE affine-invariant ensemble are not independent
chains (each move uses the others' positions), so that R-hat only flags gross non-mixing
(values >> 1.01); it is not a convergence proof. The autocorrelation rule is the stop rule.
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.data import Dataset
from bsdflab.fit.parameters import parameter
from bsdflab.fit.posterior import LogPosterior
from bsdflab.fit.sampling import RunResult
from bsdflab.util.extras import require


def arviz():
    """arviz, imported without its FutureWarning about the coming 1.0 refactor."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        az = require("arviz", "fit")
    return az


def inference_data(run: RunResult, logpost: LogPosterior, dataset: Dataset):
    """ArviZ InferenceData of the post-burn-in chains (walkers = chains), with the log
    posterior, the observed data and the run's diagnostics as attributes."""

    az = arviz()
    idata = az.from_emcee(run.sampler, var_names=list(run.names))
    idata = _observed(idata.sel(draw=slice(run.burn, None)), dataset)
    attrs = {"stop_reason": run.stop_reason, "converged": int(run.converged), "steps": run.steps,
             "burn_in": run.burn, "thin": run.thin, "walkers": int(run.chain.shape[1]),
             "tau": run.tau.tolist(), "acceptance_fraction_mean": float(np.mean(run.acceptance)),
             "map": run.map.x.tolist(), "sampling_seconds": run.seconds,
             "fixed": str(logpost.config.fixed),
             "priors": str({k: v.describe() for k, v in logpost.config.priors.items()}),
             "rhat_note": "R-hat across the walkers of one ensemble is not a convergence test "
                          "(walkers are not independent); see bsdflab.fit.diagnostics"}
    idata.posterior.attrs.update(attrs)
    return idata


def _observed(idata, dataset: Dataset):
    import xarray as xr

    rows = {"row": np.arange(len(dataset))}
    idata.add_groups(
        observed_data=xr.Dataset({"reflectance": ("row", dataset.reflectance)}, coords=rows),
        constant_data=xr.Dataset({k: ("row", getattr(dataset, k)) for k in
                                  ("sigma", "wavelength_nm", "angle_deg", "angle_out_deg", "geometry")}, coords=rows))
    return idata


def nested_inference_data(res, logpost: LogPosterior, dataset: Dataset):
    """ArviZ InferenceData of a nested run's equally weighted draws (one chain), with the
    evidence and the stop rule as attributes."""
    az = arviz()
    draws = res.draws()
    idata = _observed(az.from_dict(posterior={n: draws[None, :, j] for j, n in enumerate(res.names)}), dataset)
    idata.posterior.attrs.update({
        "sampler": "nested (dynesty)", "stop_reason": res.stop_reason, "log_evidence": res.log_evidence,
        "log_evidence_error": res.log_evidence_error, "iterations": res.iterations, "ess_kish": res.ess_kish,
        "fixed": str(logpost.config.fixed),
        "priors": str({k: v.describe() for k, v in logpost.config.priors.items()})})
    return idata


def nested_summary_rows(res, truths: dict | None = None) -> list[dict]:
    """Per free parameter: median, 90 % interval, mean, sd, the MAP draw, and Kish's ESS of
    the run's importance weights (the draws are resampled from them: no autocorrelation)."""
    draws = res.draws()
    rows = []
    for j, name in enumerate(res.names):
        q05, q50, q95 = np.quantile(draws[:, j], [0.05, 0.5, 0.95])
        row = {"parameter": name, "unit": parameter(name).unit, "median": q50, "ci90_low": q05,
               "ci90_high": q95, "mean": float(np.mean(draws[:, j])), "sd": float(np.std(draws[:, j], ddof=1)),
               "map": float(res.map.x[j]), "ess_kish": res.ess_kish}
        if truths is not None and name in truths:
            row["truth"] = float(truths[name])
        rows.append(row)
    return rows


def summary_rows(run: RunResult, idata, truths: dict | None = None) -> list[dict]:
    """Per free parameter: median, 90 % equal-tailed credible interval, mean, sd, ESS, R-hat."""
    az = arviz()
    draws = run.draws()
    ess_b = az.ess(idata, method="bulk")
    ess_t = az.ess(idata, method="tail")
    rhat = az.rhat(idata)
    ess_tau = run.ess_tau()
    rows = []
    for j, name in enumerate(run.names):
        q05, q50, q95 = np.quantile(draws[:, j], [0.05, 0.5, 0.95])
        row = {"parameter": name, "unit": parameter(name).unit, "median": q50, "ci90_low": q05,
               "ci90_high": q95, "mean": float(np.mean(draws[:, j])), "sd": float(np.std(draws[:, j], ddof=1)),
               "map": float(run.map.x[j]), "tau": float(run.tau[j]), "ess_tau": float(ess_tau[j]),
               "ess_bulk": float(ess_b[name]), "ess_tail": float(ess_t[name]),
               "rhat_walkers": float(rhat[name])}
        if truths is not None and name in truths:
            row["truth"] = float(truths[name])
        rows.append(row)
    return rows


def table_markdown(rows: list[dict]) -> str:
    """The parameter table; the emcee columns (tau, ESS, R-hat over walkers) or the nested
    ones (Kish's ESS) as the rows carry them."""
    has_truth = any("truth" in r for r in rows)
    mcmc = "tau" in rows[0]
    head = ["parameter", "unit", "median", "90 % CI", "MAP"] + (["truth"] if has_truth else []) + \
           (["τ", "ESS (τ)", "ESS bulk", "R̂ (walkers)*"] if mcmc else ["ESS (Kish)"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["parameter"], r["unit"], f"{r['median']:.5g}", f"[{r['ci90_low']:.5g}, {r['ci90_high']:.5g}]",
                 f"{r['map']:.5g}"] + ([f"{r['truth']:.5g}" if "truth" in r else ""] if has_truth else [])
        cells += ([f"{r['tau']:.1f}", f"{r['ess_tau']:.0f}", f"{r['ess_bulk']:.0f}", f"{r['rhat_walkers']:.3f}"]
                  if mcmc else [f"{r['ess_kish']:.0f}"])
        lines.append("| " + " | ".join(cells) + " |")
    lines.append("")
    if mcmc:
        lines.append("\\* R-hat over the walkers of one ensemble: walkers are not independent chains, so this "
                     "only flags gross non-mixing; convergence is judged by N > 50 τ (see the study's summary).")
    else:
        lines.append("Nested sampling (dynesty): draws resampled from the weighted dead and live points; "
                     "ESS (Kish) = (Σw)² / Σw² of their weights.")
    return "\n".join(lines) + "\n"
