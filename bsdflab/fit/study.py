"""A fitting study: data + config -> posterior -> the study folder.

Everything is written into a temporary folder beside ``out`` and renamed into place at the
end, so an interrupted study (Ctrl-C, an error) leaves no half-written folder.

Folder contents: posterior.nc (ArviZ InferenceData), parameters.md / parameters.csv,
corner.png, predictive.png, residuals.png (normalised residuals and the posterior predictive
check of each series, bsdflab.fit.checks), trace.png, appearance.png + appearance.csv, renders.png,
material.json (posterior-mean model dict), sphere.json (a scene file with it, for
``bsdflab render``), summary.json (with ``warnings``: bsdflab.fit.alerts), and copies of the data and config files.
"""
from __future__ import annotations

import csv
import io
import json
import os
import shutil
import tempfile
import time
from dataclasses import replace

import numpy as np

from bsdflab.bsdfs import from_dict
from bsdflab.fit.alerts import Alert, draw_modes, emulator_alert, fit_alerts, thickness_names
from bsdflab.fit.appearance import appearance_posterior, full_appearance
from bsdflab.fit.checks import ALPHA, normalised_residuals, predictive_checks, sidak_level
from bsdflab.fit.config import FitConfig
from bsdflab.fit.data import Dataset, read_csv
from bsdflab.fit.diagnostics import (
    inference_data,
    nested_inference_data,
    nested_summary_rows,
    summary_rows,
    table_markdown,
)
from bsdflab.fit.emulator import SHOW_PROGRESS
from bsdflab.fit.figures import (
    SYMBOLS,
    appearance_plot,
    corner_plot,
    display_exposure,
    nested_plot,
    predictive_plot,
    residual_plot,
    trace_plot,
)
from bsdflab.fit.material import material_dict
from bsdflab.fit.nested import run_nested
from bsdflab.fit.parameters import ALL_NAMES, canonical
from bsdflab.fit.posterior import LogPosterior
from bsdflab.fit.sampling import run_sampler

PREDICTIVE_DRAWS = 200


def truths_from_comments(dataset: Dataset) -> dict | None:
    """The ``truth: name=value, ...`` comment that ``bsdflab fit simulate`` writes."""
    for c in dataset.comments:
        if c.startswith("truth:"):
            out = {}
            for item in c[len("truth:"):].split(","):
                k, _, v = item.strip().partition("=")
                try:
                    out[canonical(k, "data comment: ")] = float(v)
                except ValueError:
                    return None
            return out
    return None


def _text(path: str, text: str) -> None:
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def run_study(data, config: FitConfig, out: str | os.PathLike, progress: bool = True,
              overwrite: bool = False, data_path: str | None = None) -> dict:
    """Fit ``data`` (a Dataset or a CSV path) with ``config`` and write the study to ``out``.
    Returns the summary dict (also written as summary.json)."""
    if not isinstance(data, Dataset):
        data_path = os.fspath(data)
        data = read_csv(data_path)
    out = os.path.abspath(os.fspath(out))
    if os.path.exists(out) and not overwrite:
        raise ValueError(f"--out {out} already exists (choose another folder or overwrite it)")
    parent = os.path.dirname(out)
    os.makedirs(parent, exist_ok=True)
    tmp = tempfile.mkdtemp(dir=parent, prefix=f".{os.path.basename(out)}.tmp-")
    try:
        summary = _write_study(data, config, tmp, progress, data_path)
        if os.path.exists(out):
            old = tempfile.mkdtemp(dir=parent, prefix=f".{os.path.basename(out)}.old-")
            os.replace(out, os.path.join(old, "study"))
            os.replace(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, out)
        return summary
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _write_study(data: Dataset, config: FitConfig, folder: str, progress: bool, data_path: str | None) -> dict:
    t0 = time.perf_counter()
    token = SHOW_PROGRESS.set(progress)
    try:
        logpost = LogPosterior(data, config)
    finally:
        SHOW_PROGRESS.reset(token)
    truths = truths_from_comments(data)
    nested = config.sampler.kind == "nested"
    run, rows = _sample(logpost, data, config, folder, progress, truths)

    draws = run.draws()
    rng = np.random.default_rng(config.sampler.seed + 1)
    pick = draws[rng.choice(len(draws), min(PREDICTIVE_DRAWS, len(draws)), replace=False)]
    model_draws = logpost.predict(pick)
    scales = logpost.full(pick)[:, ALL_NAMES.index("noise_scale")]
    # drawn with or without the figures, so that the draws after them do not depend on [output]
    replicated = model_draws + scales[:, None] * data.sigma[None, :] * rng.standard_normal(model_draws.shape)
    checks = predictive_checks(data, model_draws, scales)
    if config.output.figures:
        _write_figures(run, draws, truths, data, model_draws, replicated, scales, checks, config, folder)

    main, mode_note = main_mode(draws, run.names)
    mean_full = logpost.full(np.mean(main, axis=0))[0]
    ap = config.appearance
    app_draws = logpost.full(draws[rng.choice(len(draws), min(ap.draws, len(draws)), replace=False)])
    appearance = _write_appearance(app_draws, mean_full, config, folder, progress)

    # canonical form, as from_dict reads it
    material = from_dict(material_dict(mean_full, model=config.model)).to_dict()
    _text(os.path.join(folder, "material.json"), json.dumps(material, indent=1) + "\n")
    _write_scene(mean_full, folder, config.model)
    if ap.renders and config.output.figures:
        _write_renders(app_draws[:ap.renders], mean_full, ap, folder, config.sampler.seed,
                       config.model, progress, config.free)

    if data_path:
        shutil.copyfile(data_path, os.path.join(folder, "data.csv"))
    else:
        _text(os.path.join(folder, "data.csv"), data.to_csv_text())
    if config.source and os.path.isfile(config.source):
        shutil.copyfile(config.source, os.path.join(folder, "config.toml"))
    forward = _forward_summary(logpost)
    alerts = study_alerts(run, draws, config, checks, forward)
    summary = {"data": data_path, "rows": len(data), "free": list(run.names), "fixed": config.fixed,
               "sampler": config.sampler.kind, "converged": run.converged, "stop_reason": run.stop_reason}
    summary.update(_nested_summary(run) if nested else _emcee_summary(run))
    summary.update({
        "map": dict(zip(run.names, run.map.x.tolist())), "map_log_posterior": run.map.log_posterior,
        "posterior_draws": int(len(draws)),
        "appearance": appearance, "forward_model": forward,
        "predictive_checks": {"alpha": ALPHA, "level_per_check": sidak_level(len(checks)),
                              "draws": int(len(pick)), "series": [c.to_dict() for c in checks]},
        "warnings": [a.to_dict() for a in alerts],
        "posterior_mean": dict(zip(ALL_NAMES, map(float, mean_full))),
        "material_note": "material.json carries the mean film thickness: the thickness spread is a spatial "
                         "average with no counterpart in one BSDF" + mode_note,
        "parameters": rows, "seconds": time.perf_counter() - t0,
    })
    _text(os.path.join(folder, "summary.json"), json.dumps(summary, indent=1, default=float) + "\n")
    return summary


def _write_figures(run, draws, truths, data: Dataset, model_draws, replicated, scales, checks, config: FitConfig,
                   folder: str) -> None:
    """corner.png, predictive.png, residuals.png and trace.png."""
    corner_plot(draws, run.names, os.path.join(folder, "corner.png"),
                truths=[truths.get(n) for n in run.names] if truths else None)
    predictive_plot(data, model_draws, replicated, os.path.join(folder, "predictive.png"))
    residual_plot(data, normalised_residuals(data, model_draws, scales), checks, os.path.join(folder, "residuals.png"))
    if config.sampler.kind == "nested":
        nested_plot(run, os.path.join(folder, "trace.png"))
    else:
        trace_plot(run, os.path.join(folder, "trace.png"), config.sampler.tau_multiple)


def _sample(logpost, data: Dataset, config: FitConfig, folder: str, progress: bool, truths: dict):
    """Run the configured sampler; write posterior.nc and the parameter tables."""
    if config.sampler.kind == "nested":
        s = config.sampler
        run = run_nested(logpost, s.live_points, s.seed, s.dlogz, progress=progress)
        idata = nested_inference_data(run, logpost, data)
        rows = nested_summary_rows(run, truths)
    else:
        run = run_sampler(logpost, config.sampler, progress=progress)
        idata = inference_data(run, logpost, data)
        rows = summary_rows(run, idata, truths)
    idata.to_netcdf(os.path.join(folder, "posterior.nc"), engine="h5netcdf")
    _text(os.path.join(folder, "parameters.md"), table_markdown(rows))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    _text(os.path.join(folder, "parameters.csv"), buf.getvalue())
    return run, rows


def main_mode(draws: np.ndarray, names) -> tuple[np.ndarray, str]:
    """The draws of the heaviest thickness mode (all draws when there is one): the mean of a
    multi-modal posterior lies between interference orders, a thickness no draw has."""
    for name in thickness_names(names):
        x = draws[:, list(names).index(name)]
        modes = draw_modes(x)
        if len(modes) > 1:
            centres = np.array([m for m, _ in modes])
            heaviest = int(np.argmax([w for _, w in modes]))
            keep = np.argmin(np.abs(x[:, None] - centres[None, :]), axis=1) == heaviest
            return draws[keep], (f"; the posterior has {len(modes)} {name} modes: the posterior-mean material "
                                 f"and renders use the heaviest ({modes[heaviest][1]:.0%} of the draws)")
    return draws, ""


def _emcee_summary(run) -> dict:
    ess_min = float(np.min(run.ess_tau()))
    return {"walkers": int(run.chain.shape[1]), "steps": run.steps, "burn_in": run.burn, "thin": run.thin,
            "tau": dict(zip(run.names, run.tau.tolist())),
            "acceptance_fraction": {"mean": float(np.mean(run.acceptance)), "min": float(np.min(run.acceptance)),
                                    "max": float(np.max(run.acceptance))},
            "ess_tau_min": ess_min, "sampling_seconds": run.seconds, "ess_per_second": ess_min / run.seconds,
            "forward_evaluations": run.evaluations + run.map.evaluations}


def _nested_summary(run) -> dict:
    return {"log_evidence": run.log_evidence, "log_evidence_error": run.log_evidence_error,
            "evidence_note": "ln Z = ln of the integral of likelihood x prior; the Bayes factor of two models "
                             "fitted to the same data is exp(ln Z1 - ln Z2)",
            "iterations": run.iterations, "ess_kish": run.ess_kish, "sampling_seconds": run.seconds,
            "forward_evaluations": run.evaluations}


def study_alerts(run, draws: np.ndarray, config: FitConfig, checks, forward: dict) -> list[Alert]:
    """Every warning of the study, in the order a reader should act on them."""
    return fit_alerts(run, draws, config.priors, checks, figures=config.output.figures) + emulator_alert(forward)


def _write_appearance(app_draws, mean_full, config: FitConfig, folder: str, progress: bool = False) -> dict:
    """appearance.png / .csv and the summary's statement: the smooth model's specular colour;
    the full model's gloss colour and 45°:0° body colour from the solver (what roughness,
    sigma_s and the slab change, bsdflab.fit.appearance.full_appearance)."""
    ap = config.appearance
    if config.model.kind == "smooth":
        app = appearance_posterior(app_draws, mean_full, ap.angles_deg, config.model.thickness_nodes,
                                   config.model.angle_nodes)
    else:
        app = full_appearance(app_draws, mean_full, config.free, ap.angles_deg, config.model, progress)
    exposure = (appearance_plot(app, os.path.join(folder, "appearance.png")) if config.output.figures
                else display_exposure(app))
    iv = app.interval(0.9)
    lines = ["angle_deg,delta_e00_median,delta_e00_p05,delta_e00_p95,delta_e00_p90"]
    lines += [f"{a:g},{m:.4f},{lo:.4f},{hi:.4f},{b:.4f}"
              for a, m, lo, hi, b in zip(app.angles_deg, iv["median"], iv["low"], iv["high"], iv["bound"])]
    k = int(np.argmin(np.abs(app.angles_deg - 30.0)))
    what = "specular" if config.model.kind == "smooth" else "gloss"
    out = {"angle_deg": float(app.angles_deg[k]), "delta_e00_p90": float(iv["bound"][k]),
           "statement": f"the {what} colour at {app.angles_deg[k]:g} deg is known to within "
                        f"dE00 <= {iv['bound'][k]:.2f} (90 % of posterior draws)",
           "display_exposure_stops": exposure}
    if app.body_delta_e is not None:
        q = np.quantile(app.body_delta_e, [0.5, 0.05, 0.95, 0.9])
        lines.append("body_45_0," + ",".join(f"{x:.4f}" for x in q))
        out["body_delta_e00_p90"] = float(q[3])
        out["statement"] += (f"; the body colour (45°:0°) to within dE00 <= {q[3]:.2f} (solver at the posterior "
                             "mean, expanded to second order over the draws)")
    _text(os.path.join(folder, "appearance.csv"), "\n".join(lines) + "\n")
    return out


def _forward_summary(logpost: LogPosterior) -> dict:
    m = logpost.model
    out = {"kind": logpost.config.model.kind}
    if hasattr(m, "max_relative_error"):
        out.update(emulator_solves=m.solves, emulator_nodes=logpost.config.model.emulator_nodes,
                   emulator_boxes={a.name: [a.lo, a.hi] for a in m.axes},
                   emulator_max_relative_error=m.max_relative_error, emulator_max_error_sigma=m.max_error_sigma)
    return out


def _write_scene(values, folder: str, model) -> None:
    from bsdflab.fit.renders import sphere_scene
    from bsdflab.scenes.scene_file import save_scene

    scene = sphere_scene(values, 320, model)
    mat = scene.materials["object"]
    bsdf = material_dict(values, model=model)
    full = replace(scene, materials={**scene.materials, "object": replace(mat, bsdf=bsdf)})
    save_scene(full, os.path.join(folder, "sphere.json"))


def render_label(name: str, v: np.ndarray, model, free=()) -> str:
    """A render's caption with the thickness it was rendered with (film or platelets) and the
    values of up to three other free parameters (what differs between the draws)."""
    parts = []
    if model.kind == "full" and model.film == "stack":
        parts.append(f"{model.platelets} x {v[ALL_NAMES.index('platelet_nm')]:.1f} nm")
    elif not (model.kind == "full" and model.film == "none"):
        parts.append(f"d = {v[ALL_NAMES.index('film_thickness_nm')]:.1f} nm")
    others = [n for n in free if n not in ("film_thickness_nm", "platelet_nm", "noise_scale")][:3]
    parts += [f"{SYMBOLS.get(n, n)} {v[ALL_NAMES.index(n)]:.3g}" for n in others]
    return f"{name}: " + ", ".join(parts) if parts else name


def _write_renders(draws_full, mean_full, ap, folder: str, seed: int, model, progress: bool = False,
                   free=()) -> None:
    from bsdflab.fit.renders import render_draws
    from bsdflab.plots.contact_sheet import contact_sheet

    values = [mean_full, *draws_full]
    labels = [render_label(name, v, model, free) for name, v in
              zip(["posterior mean"] + [f"draw {i + 1}" for i in range(len(draws_full))], values)]
    items = render_draws(values, labels, ap.render_size, ap.render_spp, seed, model, progress)
    contact_sheet(items, os.path.join(folder, "renders.png"), title="sphere renders of posterior draws",
                  columns=min(len(items), 5))
