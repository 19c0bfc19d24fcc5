"""A fitting study: data + config -> posterior -> the study folder.

Everything is written into a temporary folder beside ``out`` and renamed into place at the
end, so an interrupted study (Ctrl-C, an error) leaves no half-written folder.

Folder contents: posterior.nc (ArviZ InferenceData), parameters.md / parameters.csv,
corner.png, predictive.png, trace.png, appearance.png + appearance.csv, renders.png,
material.json (posterior-mean model dict), sphere.json (a scene file with it, for
``bsdflab render``), summary.json, and copies of the data and config files.
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
from bsdflab.fit.appearance import appearance_posterior, gloss_vectors
from bsdflab.fit.config import FitConfig
from bsdflab.fit.data import Dataset, read_csv
from bsdflab.fit.diagnostics import inference_data, summary_rows, table_markdown
from bsdflab.fit.figures import appearance_plot, corner_plot, predictive_plot, trace_plot
from bsdflab.fit.material import material_dict
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
    logpost = LogPosterior(data, config)
    run = run_sampler(logpost, config.sampler, progress=progress)
    truths = truths_from_comments(data)
    idata = inference_data(run, logpost, data)
    idata.to_netcdf(os.path.join(folder, "posterior.nc"), engine="h5netcdf")

    rows = summary_rows(run, idata, truths)
    _text(os.path.join(folder, "parameters.md"), table_markdown(rows))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    _text(os.path.join(folder, "parameters.csv"), buf.getvalue())

    draws = run.draws()
    rng = np.random.default_rng(config.sampler.seed + 1)
    corner_plot(draws, run.names, os.path.join(folder, "corner.png"),
                truths=[truths.get(n) for n in run.names] if truths else None)
    pick = draws[rng.choice(len(draws), min(PREDICTIVE_DRAWS, len(draws)), replace=False)]
    model_draws = logpost.predict(pick)
    noise = logpost.full(pick)[:, ALL_NAMES.index("noise_scale")][:, None] * data.sigma[None, :]
    predictive_plot(data, model_draws, model_draws + noise * rng.standard_normal(model_draws.shape),
                    os.path.join(folder, "predictive.png"))
    trace_plot(run, os.path.join(folder, "trace.png"), config.sampler.tau_multiple)

    mean_full = logpost.full(np.mean(draws, axis=0))[0]
    ap = config.appearance
    app_draws = logpost.full(draws[rng.choice(len(draws), min(ap.draws, len(draws)), replace=False)])
    appearance = _write_appearance(app_draws, mean_full, config, folder)

    # canonical form, as from_dict reads it
    material = from_dict(material_dict(mean_full, model=config.model)).to_dict()
    _text(os.path.join(folder, "material.json"), json.dumps(material, indent=1) + "\n")
    _write_scene(mean_full, folder, config.model)
    if ap.renders:
        _write_renders(app_draws[:ap.renders], mean_full, ap, folder, config.sampler.seed,
                       config.model)

    if data_path:
        shutil.copyfile(data_path, os.path.join(folder, "data.csv"))
    else:
        _text(os.path.join(folder, "data.csv"), data.to_csv_text())
    if config.source and os.path.isfile(config.source):
        shutil.copyfile(config.source, os.path.join(folder, "config.toml"))
    ess_min = float(np.min(run.ess_tau()))
    summary = {
        "data": data_path, "rows": len(data), "free": list(run.names), "fixed": config.fixed,
        "walkers": int(run.chain.shape[1]), "steps": run.steps, "converged": run.converged,
        "stop_reason": run.stop_reason, "burn_in": run.burn, "thin": run.thin,
        "tau": dict(zip(run.names, run.tau.tolist())),
        "acceptance_fraction": {"mean": float(np.mean(run.acceptance)), "min": float(np.min(run.acceptance)),
                                "max": float(np.max(run.acceptance))},
        "map": dict(zip(run.names, run.map.x.tolist())), "map_log_posterior": run.map.log_posterior,
        "posterior_draws": int(len(draws)), "ess_tau_min": ess_min,
        "sampling_seconds": run.seconds, "ess_per_second": ess_min / run.seconds,
        "forward_evaluations": run.evaluations + run.map.evaluations,
        "appearance": appearance, "forward_model": _forward_summary(logpost),
        "posterior_mean": dict(zip(ALL_NAMES, map(float, mean_full))),
        "material_note": "material.json carries the mean film thickness: the thickness spread is a spatial "
                         "average with no counterpart in one BSDF",
        "parameters": rows, "seconds": time.perf_counter() - t0,
    }
    _text(os.path.join(folder, "summary.json"), json.dumps(summary, indent=1, default=float) + "\n")
    return summary


def _write_appearance(app_draws, mean_full, config: FitConfig, folder: str) -> dict:
    """appearance.png / .csv and the summary's statement (the smooth model's specular colour;
    the full model's gloss colour, see ``gloss_vectors``; none for a platelet stack)."""
    draws, mean = gloss_vectors(app_draws, config.model), gloss_vectors(mean_full, config.model)
    if draws is None:
        return {"statement": "not computed: the appearance posterior uses the smooth model's specular "
                             "spectra, which have one film (not a platelet stack)"}
    ap = config.appearance
    app = appearance_posterior(draws, mean, ap.angles_deg, config.model.thickness_nodes, config.model.angle_nodes)
    exposure = appearance_plot(app, os.path.join(folder, "appearance.png"))
    iv = app.interval(0.9)
    lines = ["angle_deg,delta_e00_median,delta_e00_p05,delta_e00_p95,delta_e00_p90"]
    lines += [f"{a:g},{m:.4f},{lo:.4f},{hi:.4f},{b:.4f}"
              for a, m, lo, hi, b in zip(app.angles_deg, iv["median"], iv["low"], iv["high"], iv["bound"])]
    _text(os.path.join(folder, "appearance.csv"), "\n".join(lines) + "\n")
    k = int(np.argmin(np.abs(app.angles_deg - 30.0)))
    what = "specular" if config.model.kind == "smooth" else "gloss"
    return {"angle_deg": float(app.angles_deg[k]), "delta_e00_p90": float(iv["bound"][k]),
            "statement": f"the {what} colour at {app.angles_deg[k]:g} deg is known to within "
                         f"dE00 <= {iv['bound'][k]:.2f} (90 % of posterior draws)",
            "display_exposure_stops": exposure}


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


def _write_renders(draws_full, mean_full, ap, folder: str, seed: int, model) -> None:
    from bsdflab.fit.renders import render_draws
    from bsdflab.plots.contact_sheet import contact_sheet

    values = [mean_full, *draws_full]
    labels = ["posterior mean"] + [f"draw {i + 1}" + (f": d = {v[0]:.1f} nm" if np.isfinite(v[0]) else "")
                                   for i, v in enumerate(draws_full)]
    items = render_draws(values, labels, ap.render_size, ap.render_spp, seed, model)
    contact_sheet(items, os.path.join(folder, "renders.png"), title="sphere renders of posterior draws",
                  columns=min(len(items), 5))
