"""The study's figures (matplotlib, Agg): corner plot, posterior predictive bands,
traces with the autocorrelation time, and the appearance posterior."""
from __future__ import annotations

import math

import numpy as np

from bsdflab.fit.appearance import AppearancePosterior
from bsdflab.fit.data import Dataset
from bsdflab.fit.parameters import parameter
from bsdflab.fit.sampling import RunResult
from bsdflab.plots.lobe import save_figure
from bsdflab.render.image_io import tone_map
from bsdflab.util.extras import require

# short titles over the corner plot's diagonal (the axis labels carry the full names)
SYMBOLS = {"film_thickness_nm": "d", "film_thickness_spread_nm": "σ_d", "film_ior": "A", "film_cauchy_b": "B",
           "substrate_ior": "n_s", "exterior_ior": "n_e", "pigment_absorption": "σ_a(550)",
           "absorption_exponent": "exponent", "slab_thickness_um": "h", "base_albedo": "ρ", "noise_scale": "s",
           "roughness": "α", "sigma_s": "σ_s", "hg_g": "g", "platelet_nm": "d_p", "gap_nm": "d_gap",
           "gap_ior": "n_gap"}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _label(name: str) -> str:
    try:
        unit = parameter(name).unit
    except ValueError:  # a structure fit's parameter (bsdflab.fit.structure): the name says it
        return name
    return f"{name} [{unit}]" if unit else name


def corner_plot(draws: np.ndarray, names, path: str, truths=None) -> None:
    corner = require("corner", "fit")
    plt = _plt()
    k = draws.shape[1]
    side = max(2.6 * k, 4.0)  # one or two parameters: room for the title and the quantile labels
    fig = corner.corner(draws, fig=plt.figure(figsize=(side, side)), labels=[_label(n) for n in names],
                        quantiles=[0.05, 0.5, 0.95], show_titles=True, title_fmt=".4g", title_kwargs={"fontsize": 7},
                        titles=[SYMBOLS.get(n, n) for n in names],
                        label_kwargs={"fontsize": 8}, truths=truths if k > 1 else None, truth_color="tab:red")
    if k == 1 and truths is not None and truths[0] is not None:
        fig.axes[0].axvline(truths[0], color="tab:red")   # corner's truth lines index a 2-D axes grid
    fig.suptitle("posterior (lines: 5 %, 50 %, 95 %" + ("; red: truth)" if truths is not None else ")"),
                 fontsize=9, y=1.0)
    save_figure(fig, path)
    plt.close(fig)


def predictive_plot(dataset: Dataset, model_draws: np.ndarray, predictive_draws: np.ndarray, path: str) -> None:
    """One panel per measured curve: data +- sigma, the model's 90 % band and the
    posterior predictive 90 % band (model + noise)."""
    plt = _plt()
    groups = dataset.groups()
    cols = min(3, len(groups))
    rows = math.ceil(len(groups) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.0 * rows), squeeze=False)
    for ax in axes.ravel()[len(groups):]:
        ax.axis("off")
    for ax, (label, idx) in zip(axes.ravel(), groups):
        wl = dataset.wavelength_nm[idx]
        pq = np.quantile(predictive_draws[:, idx], [0.05, 0.95], axis=0)
        mq = np.quantile(model_draws[:, idx], [0.05, 0.5, 0.95], axis=0)
        x = wl
        if len(wl) == 1:  # one wavelength (a gonio row): bands of zero width would not show
            x, pq, mq = wl + np.array([-4.0, 4.0]), np.repeat(pq, 2, axis=1), np.repeat(mq, 2, axis=1)
        ax.fill_between(x, pq[0], pq[1], color="tab:blue", alpha=0.18, lw=0, label="predictive 90 %")
        ax.fill_between(x, mq[0], mq[2], color="tab:blue", alpha=0.45, lw=0, label="model 90 %")
        ax.plot(x, mq[1], color="tab:blue", lw=1.0, label="model median")
        ax.errorbar(wl, dataset.reflectance[idx], dataset.sigma[idx], fmt=".", ms=3, color="k", lw=0.7,
                    label="data ± σ")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("wavelength [nm]", fontsize=8)
        ax.set_ylabel("reflectance" if label.startswith(("specular", "total")) else "π f (reflectance factor)",
                      fontsize=8)
        ax.tick_params(labelsize=7)
    axes.ravel()[0].legend(fontsize=6, loc="best")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def trace_plot(run: RunResult, path: str, tau_multiple: float = 50.0) -> None:
    plt = _plt()
    k = len(run.names)
    fig, axes = plt.subplots(k + 1, 1, figsize=(8, 1.6 * (k + 1) + 0.4), squeeze=False)
    steps = np.arange(run.steps)
    for j, name in enumerate(run.names):
        ax = axes[j, 0]
        ax.plot(steps, run.chain[:, :, j], color="k", alpha=max(0.05, 3.0 / run.chain.shape[1]), lw=0.5)
        ax.axvline(run.burn, color="tab:red", lw=0.8)
        ax.set_ylabel(name, fontsize=7)
        ax.tick_params(labelsize=7)
    ax = axes[k, 0]
    ns = np.array([n for n, _ in run.tau_history])
    taus = np.array([t for _, t in run.tau_history])
    for j, name in enumerate(run.names):
        ax.plot(ns, taus[:, j], marker=".", lw=0.8, label=name)
    ax.plot(ns, ns / tau_multiple, "k--", lw=0.8, label=f"N / {tau_multiple:g} (stop when τ is below)")
    ax.set_xlabel("step N", fontsize=8)
    ax.set_ylabel("τ estimate", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=6, ncol=3)
    axes[0, 0].set_title(f"walkers (red: burn-in {run.burn}); {run.stop_reason}", fontsize=7)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def display_exposure(app: AppearancePosterior) -> float:
    """The stops that bring the brightest mean colour to 0.9 of the display's white."""
    peak = float(np.max(app.rgb_mean))
    return math.log2(0.9 / peak) if peak > 0 else 0.0


def appearance_plot(app: AppearancePosterior, path: str) -> float:
    """Colour strips per draw (rows) vs angle (columns) and the Delta E00 interval per
    angle. Returns the display exposure (stops) the strips were brightened by."""
    plt = _plt()
    exposure = display_exposure(app)
    strips = tone_map(np.vstack([app.rgb_mean[None], app.rgb]).astype(np.float32), exposure)
    iv = app.interval(0.9)
    fig, (a0, a1) = plt.subplots(2, 1, figsize=(7.5, 6.8), gridspec_kw={"height_ratios": [1.4, 1]})
    a = app.angles_deg
    step = (a[1] - a[0]) if len(a) > 1 else 1.0
    a0.imshow(strips, aspect="auto", interpolation="nearest",
              extent=(a[0] - step / 2, a[-1] + step / 2, len(app.rgb) + 0.5, -0.5))
    a0.axhline(0.5, color="w", lw=1.0)
    a0.set_ylabel("row 0: posterior mean; 1..: draws", fontsize=8)
    what = "specular" if app.body_delta_e is None else "gloss"
    a0.set_title(f"{what} colour vs angle (sRGB, D65; display exposure {exposure:+.1f} stops)", fontsize=9)
    a1.fill_between(a, iv["low"], iv["high"], color="tab:purple", alpha=0.3, lw=0, label="5-95 %")
    a1.plot(a, iv["median"], color="tab:purple", label="median")
    a1.plot(a, iv["bound"], "k--", lw=0.9, label="90 % of draws below")
    if app.body_delta_e is not None:
        a1.axhline(float(np.quantile(app.body_delta_e, 0.9)), color="tab:brown", lw=0.9,
                   label="body colour 45°:0°, 90 % below")
    a1.set_xlabel("angle of incidence = viewing angle [deg]", fontsize=8)
    a1.set_ylabel("ΔE00 to posterior mean", fontsize=8)
    a1.legend(fontsize=7)
    for ax in (a0, a1):
        ax.tick_params(labelsize=7)
        ax.set_xlim(a[0] - step / 2, a[-1] + step / 2)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
    return exposure


def residual_plot(dataset: Dataset, residuals: np.ndarray, checks, path: str) -> None:
    """Normalised residuals (y - model) / (s sigma) per measured curve, with the +-2 and +-3
    lines and each curve's predictive p-value (bsdflab.fit.checks). More than 12 curves (gonio
    rows, one wavelength each) are drawn one panel per geometry against the row number."""
    plt = _plt()
    p_of = {c.series: c for c in checks}
    groups = dataset.groups()
    if len(groups) > 12:
        from bsdflab.fit.data import GEOMETRIES

        groups = [(GEOMETRIES[g], np.flatnonzero(dataset.geometry == g)) for g in np.unique(dataset.geometry)]
    cols = min(3, len(groups))
    rows = math.ceil(len(groups) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.6 * rows), squeeze=False)
    for ax in axes.ravel()[len(groups):]:
        ax.axis("off")
    for ax, (label, idx) in zip(axes.ravel(), groups):
        per_curve = label in p_of
        x = dataset.wavelength_nm[idx] if per_curve else np.arange(len(idx))
        r = residuals[idx]
        for k, style in ((2, ":"), (3, "--")):
            ax.axhline(k, color="0.5", ls=style, lw=0.7)
            ax.axhline(-k, color="0.5", ls=style, lw=0.7)
        ax.axhline(0, color="k", lw=0.6)
        ax.plot(x, r, ".-" if per_curve else ".", ms=3, lw=0.6, color="tab:red" if per_curve and p_of[label].flagged
                else "tab:blue")
        title = label
        if per_curve:
            c = p_of[label]
            title += f"  p = {c.p_value:.2g}  χ²/n = {c.chi2_per_row:.2f}" + ("  FAILS" if c.flagged else "")
        ax.set_title(title, fontsize=8)
        ax.set_xlabel("wavelength [nm]" if per_curve else "row", fontsize=8)
        ax.set_ylabel("(y − model) / (s σ)", fontsize=8)
        ax.tick_params(labelsize=7)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def nested_plot(res, path: str) -> None:
    """A nested run: ln L of the dead points against the prior volume ln X, and their
    posterior weights (the mass the run found; several peaks in the weights over ln X do
    not mean several modes, which the corner plot shows)."""
    plt = _plt()
    r = res.results
    logx = np.asarray(r.logvol)
    w = np.exp(r.logwt - np.max(r.logwt))
    fig, (a0, a1) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    a0.plot(logx, r.logl, lw=0.8, color="k")
    a0.set_ylabel("ln L", fontsize=8)
    a0.set_title(res.stop_reason, fontsize=7)
    a1.plot(logx, w / np.max(w), lw=0.8, color="tab:blue")
    a1.set_ylabel("posterior weight (max 1)", fontsize=8)
    a1.set_xlabel("ln X (prior volume left)", fontsize=8)
    for ax in (a0, a1):
        ax.tick_params(labelsize=7)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
