"""The study folder of a structure fit (a config with ``[structure]``; docs/fit.md):
posterior draws, parameter table, corner, predictive, residual and trace figures,
summary.json, the inputs. summary.json carries the predictive checks (bsdflab.fit.checks,
per dataset and series: a row's model value comes through its dataset's instrument) and the
warnings (bsdflab.fit.alerts). Written into a temporary folder beside ``out`` and renamed at
the end, like bsdflab.fit.study; material.json is the posterior median as a renderable model
(the smooth stack's: bsdflab.fit.stack_material; the full model's Layered). The snake study's
appearance and renders have no counterpart for a general stack."""
from __future__ import annotations

import csv
import io
import json
import os
import shutil
import tempfile
import time

import numpy as np

from bsdflab.bsdfs import from_dict
from bsdflab.fit.alerts import emulator_alert, fit_alerts
from bsdflab.fit.checks import ALPHA, normalised_residuals, predictive_checks, sidak_level
from bsdflab.fit.data import Dataset, read_csv
from bsdflab.fit.figures import corner_plot, predictive_plot, residual_plot, trace_plot
from bsdflab.fit.sampling import run_sampler
from bsdflab.fit.stack_config import StackConfig
from bsdflab.fit.stack_posterior import StackPosterior
from bsdflab.util.files import write_atomically

PREDICTIVE_DRAWS = 200


def load_datasets(config: StackConfig, data=None) -> list[Dataset]:
    """The config's datasets: the [[dataset]] files, or ``data`` (a Dataset or CSV path) for a
    config without [[dataset]]."""
    if config.datasets[0].data is None:
        if data is None:
            raise ValueError("this config has no [[dataset]] entries: give the data file")
        return [data if isinstance(data, Dataset) else read_csv(data)]
    if data is not None:
        raise ValueError("this config names its data in [[dataset]] entries: give no data file")
    return [read_csv(s.data) for s in config.datasets]


def _text(path: str, text: str) -> None:
    def write(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
    write_atomically(path, write, suffix=".tmp")


def run_stack_study(config: StackConfig, out, data=None, progress: bool = True, overwrite: bool = False) -> dict:
    datasets = load_datasets(config, data)
    out = os.path.abspath(os.fspath(out))
    if os.path.exists(out) and not overwrite:
        raise ValueError(f"--out {out} already exists (choose another folder or overwrite it)")
    parent = os.path.dirname(out)
    os.makedirs(parent, exist_ok=True)
    tmp = tempfile.mkdtemp(dir=parent, prefix=f".{os.path.basename(out)}.tmp-")
    try:
        summary = _write(datasets, config, tmp, progress)
        if os.path.exists(out):
            shutil.rmtree(out)
        os.replace(tmp, out)
        return summary
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _posterior(datasets, config, progress: bool):
    """The posterior of a structure fit: the smooth stack's, or the full model's
    (bsdflab.fit.full_stack_config, [model] kind = "full"; its emulator's solves under a
    progress bar)."""
    from bsdflab.fit.full_stack_config import FullStackConfig

    if isinstance(config, FullStackConfig):
        from bsdflab.fit.emulator import SHOW_PROGRESS
        from bsdflab.fit.full_stack_posterior import FullStackPosterior

        token = SHOW_PROGRESS.set(progress)
        try:
            return FullStackPosterior(datasets, config)
        finally:
            SHOW_PROGRESS.reset(token)
    return StackPosterior(datasets, config)


def _write_material(post, median: np.ndarray, folder: str, summary: dict) -> None:
    """material.json: the posterior median as a renderable model (the full model's Layered,
    or the smooth stack's: bsdflab.fit.stack_material), in its canonical (to_dict) form;
    summary.json's material_note says what it carries, or why there is none."""
    try:
        model = from_dict(post.material_dict(median)).to_dict()
    except ValueError as e:        # e.g. more film layers than an interface takes
        summary["material_note"] = f"no material.json: {e}"
        return
    if hasattr(post, "material_note"):
        summary["material_note"] = post.material_note(median)
    _text(os.path.join(folder, "material.json"), json.dumps(model, indent=1) + "\n")


def _write(datasets, config: StackConfig, folder: str, progress: bool) -> dict:
    t0 = time.perf_counter()
    post = _posterior(datasets, config, progress)
    run = run_sampler(post, config.sampler, progress=progress)
    draws = run.draws()
    rows = []
    for j, name in enumerate(run.names):
        q = np.quantile(draws[:, j], [0.0015, 0.05, 0.5, 0.95, 0.9985])
        p = post.config.domains[name]
        rows.append({"parameter": name, "unit": p.unit, "median": q[2], "ci90_low": q[1], "ci90_high": q[3],
                     "ci997_low": q[0], "ci997_high": q[4], "map": float(run.map.x[j]), "tau": float(run.tau[j]),
                     "at_domain_bound": bool(np.isclose(q[2], p.lo) or np.isclose(q[2], p.hi))})
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    _text(os.path.join(folder, "parameters.csv"), buf.getvalue())
    md = ["| parameter | unit | median | 90 % CI | 99.7 % CI | MAP | τ |", "|---|---|---|---|---|---|---|"]
    md += [f"| {r['parameter']} | {r['unit']} | {r['median']:.5g} | [{r['ci90_low']:.5g}, {r['ci90_high']:.5g}] | "
           f"[{r['ci997_low']:.5g}, {r['ci997_high']:.5g}] | {r['map']:.5g} | {r['tau']:.1f} |" for r in rows]
    _text(os.path.join(folder, "parameters.md"), "\n".join(md) + "\n")
    rng = np.random.default_rng(config.sampler.seed + 1)
    figures = config.output.figures
    if figures:
        corner_plot(draws, run.names, os.path.join(folder, "corner.png"))
    pick = draws[rng.choice(len(draws), min(PREDICTIVE_DRAWS, len(draws)), replace=False)]
    model = post.predict(pick)
    scales = post.named(pick)["noise_scale"]
    noise = scales[:, None] * post.dataset.sigma[None, :]
    if figures:
        predictive_plot(post.dataset, model, model + noise * rng.standard_normal(model.shape),
                        os.path.join(folder, "predictive.png"))
    checks = predictive_checks(post.dataset, model, scales)
    if figures:
        residual_plot(post.dataset, normalised_residuals(post.dataset, model, scales), checks,
                      os.path.join(folder, "residuals.png"))
    extra = post.summary_extra() if hasattr(post, "summary_extra") else {}
    emulator = extra.get("emulator") or {}   # the full model's, as the snake study warns of it
    alerts = fit_alerts(run, draws, post.config.priors, checks, post.config.domains, figures)
    alerts += emulator_alert({"emulator_max_error_sigma": emulator.get("max_error_sigma")})
    if figures:
        trace_plot(run, os.path.join(folder, "trace.png"), config.sampler.tau_multiple)
    np.savez_compressed(os.path.join(folder, "draws.npz"), draws=draws, names=np.array(run.names))
    for spec, d in zip(config.datasets, datasets, strict=True):
        _text(os.path.join(folder, f"data{'_' + spec.name if spec.name else ''}.csv"), d.to_csv_text())
    if config.source and os.path.isfile(config.source):
        shutil.copyfile(config.source, os.path.join(folder, "config.toml"))
    summary = {
        "model": "structure", "rows": len(post.dataset), "datasets": [s.name or "data" for s in config.datasets],
        "free": list(run.names), "fixed": post.config.fixed, "walkers": int(run.chain.shape[1]), "steps": run.steps,
        "converged": run.converged, "stop_reason": run.stop_reason, "tau": dict(zip(run.names, run.tau.tolist())),
        "acceptance_fraction": float(np.mean(run.acceptance)), "map": dict(zip(run.names, run.map.x.tolist())),
        "posterior_draws": int(len(draws)), "sampling_seconds": run.seconds,
        "forward_evaluations": run.evaluations + run.map.evaluations, "parameters": rows,
        "predictive_checks": {"alpha": ALPHA, "level_per_check": sidak_level(len(checks)),
                              "draws": int(len(pick)), "series": [c.to_dict() for c in checks]},
        "warnings": [a.to_dict() for a in alerts],
        "seconds": time.perf_counter() - t0,
    }
    summary.update(extra)
    _write_material(post, np.median(draws, axis=0), folder, summary)
    _text(os.path.join(folder, "summary.json"), json.dumps(summary, indent=1, default=float) + "\n")
    return summary
