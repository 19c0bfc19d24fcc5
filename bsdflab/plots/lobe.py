"""The lobe figure: in-plane scattering lobe plus albedo vs incidence angle."""
from __future__ import annotations

import numpy as np

from bsdflab.bsdfs import BSDF
from bsdflab.lobes import Lobe
from bsdflab.util.files import write_atomically


def _in_plane(theta: np.ndarray) -> np.ndarray:
    """Directions in the x-z plane at signed polar angle theta (from +z toward +x)."""
    return np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)


def _albedo(bsdf: BSDF, wi: np.ndarray, lobes: Lobe, samples: int, seed: int) -> np.ndarray:
    """Mean sample weight for one incident direction (linear sRGB)."""
    s = bsdf.sample(np.repeat(wi[None], samples, axis=0), seed=seed, lobes=lobes)
    return s.weight.mean(axis=0)


def _display(rgb: np.ndarray) -> np.ndarray:
    """Linear sRGB -> displayable sRGB in [0, 1] (colour-science's encoding)."""
    import colour

    return np.clip(colour.cctf_encoding(np.clip(rgb, 0, None), function="sRGB"), 0, 1)


def lobe_figure(bsdf: BSDF, theta_i: float, path: str, samples: int = 200_000,
                seed: int = 0) -> dict[str, np.ndarray]:
    """Write the figure to `path` (PNG, atomically) and return albedos (linear sRGB)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    wi = _in_plane(np.array([-theta_i]))[0]  # light from the -x side
    fig = plt.figure(figsize=(15, 4.6), constrained_layout=True)
    lobe_panel(fig.add_subplot(1, 3, 1, projection="polar"), bsdf, wi, samples, seed)
    summary = {}

    _hemisphere_panel(fig.add_subplot(1, 3, 2), bsdf, wi)

    # Albedo vs incidence angle, per lobe kind, with the colour as a swatch strip.
    ax2 = fig.add_subplot(1, 3, 3)
    angles = np.radians(np.linspace(0, 89, 46))
    n = max(2000, samples // 50)
    parts = [(Lobe.REFLECTION, "reflected"), (Lobe.TRANSMISSION, "transmitted")]
    for lobe, label in parts:
        if not bsdf.lobes & lobe:
            continue
        alb = np.array([_albedo(bsdf, _in_plane(np.array([-a]))[0], lobe, n, seed) for a in angles])
        ax2.plot(np.degrees(angles), alb.mean(axis=1), color="k", lw=1.5,
                 ls="-" if lobe == Lobe.REFLECTION else "--", label=f"{label} (mean of RGB)")
        ax2.scatter(np.degrees(angles), alb.mean(axis=1), c=_display(alb), s=40, zorder=3,
                    edgecolors="0.3", linewidths=0.4)
    ax2.set_xlabel("incidence angle [deg]")
    ax2.set_ylabel("albedo (dots in their sRGB colour)")
    ax2.set_ylim(0, 1.05)
    ax2.grid(alpha=0.3)
    ax2.legend(fontsize=8)
    ax2.set_title(f"{bsdf.to_dict()['type']}: albedo vs angle", fontsize=10)

    for lobe, name in ((Lobe.REFLECTION, "albedo_R"), (Lobe.TRANSMISSION, "albedo_T")):
        if bsdf.lobes & lobe:
            summary[name] = _albedo(bsdf, wi, lobe, samples, seed)
    save_figure(fig, path)
    plt.close(fig)
    return summary


LOG_DECADES = 4  # dynamic range of the polar plot: a glossy peak and a body lobe 10^3 below it both show


def log_radius(values: np.ndarray, peak: float) -> np.ndarray:
    """Radius of the polar lobe plot: decades above peak * 10^-LOG_DECADES (0 below it).
    A linear radius shrinks the body lobe of a glossy material to a dot beside its peak."""
    floor = peak * 10.0**-LOG_DECADES
    return np.log10(np.maximum(values, floor) / floor)


def lobe_panel(ax, bsdf: BSDF, wi: np.ndarray, samples: int = 200_000, seed: int = 0) -> None:
    """The in-plane lobe on polar axes, radius logarithmic in f (LOG_DECADES decades), delta
    lobes as arrows, the legend outside the axes (it covered the angle labels inside)."""
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    ax.set_thetamin(-180)
    ax.set_thetamax(180)
    smooth = bsdf.lobes & Lobe.SMOOTH
    delta = []
    if bsdf.lobes & Lobe.DELTA:
        s = bsdf.sample(np.repeat(wi[None], samples, axis=0), seed=seed)
        for lobe, label in ((Lobe.DELTA_REFLECTION, "reflection"), (Lobe.DELTA_TRANSMISSION, "transmission")):
            hit = s.lobe == int(lobe)
            if np.any(hit):
                wo = s.wo[hit][0]
                delta.append((label, np.arctan2(wo[0], wo[2]), s.weight[hit].sum(axis=0) / samples))
    t = np.linspace(-np.pi, np.pi, 721)
    f = np.zeros((len(t), 3))
    if smooth:
        wo = _in_plane(t)
        f = bsdf.eval(wi, wo) / np.maximum(np.abs(wo[:, 2]), 1e-9)[:, None]  # BSDF value
    peak = max([float(f.max())] + [float(e.mean()) for _, _, e in delta] + [1e-12])
    if smooth:
        for c, colour_name in enumerate(("tab:red", "tab:green", "tab:blue")):
            ax.plot(t, log_radius(f[:, c], peak), color=colour_name, lw=1.2, label="RGB"[c])
    for label, angle, energy in delta:
        r = float(log_radius(np.array([energy.mean()]), peak)[0])
        ax.annotate("", xy=(angle, r), xytext=(0, 0),
                    arrowprops=dict(arrowstyle="->", lw=2.5, color=_display(energy)))
        ax.text(angle, r * 1.05, f"delta {label}\nRGB {np.round(energy, 3)}", fontsize=8, ha="center")
    ax.set_rlim(0, LOG_DECADES * 1.08)
    ticks = np.arange(LOG_DECADES + 1)
    ax.set_rticks(ticks)
    ax.set_yticklabels([f"{peak * 10.0**(k - LOG_DECADES):.2g}" for k in ticks], fontsize=7)
    what = "f(wi, wo) [1/sr]" if smooth else ""
    what += (" and " if smooth and delta else "") + ("delta lobes: arrow = energy fraction" if delta else "")
    ax.set_title(f"in the plane of incidence, log radius: {what}", fontsize=10)
    top = LOG_DECADES * 0.9
    ax.annotate("", xy=(0, 0), xytext=(np.arctan2(wi[0], wi[2]), top),
                arrowprops=dict(arrowstyle="->", lw=1.5, color="0.4"))
    ax.text(np.arctan2(wi[0], wi[2]), top * 1.06, "incident", fontsize=8, color="0.4", ha="center")
    if smooth:
        ax.legend(loc="upper left", bbox_to_anchor=(1.05, 1.0), fontsize=8, borderaxespad=0)


HEMISPHERE_RES = 48
HEMISPHERE_WALKS = 64  # walks per pixel for stochastic (layered) models


def _hemisphere_panel(ax, bsdf: BSDF, wi: np.ndarray) -> None:
    """f cos(theta_o) over the upper hemisphere (orthographic view from above) in sRGB,
    normalised to its maximum for display."""
    x = np.linspace(-1, 1, HEMISPHERE_RES)
    X, Y = np.meshgrid(x, -x)
    inside = X**2 + Y**2 < 1
    wo = np.stack([X[inside], Y[inside], np.sqrt(1 - X[inside]**2 - Y[inside]**2)], axis=1)
    if hasattr(bsdf, "eval_with_error"):
        values = bsdf.eval_with_error(wi, wo, samples=HEMISPHERE_WALKS, error_walks=0)[0]  # no error shown
    else:
        values = bsdf.eval(wi, wo)
    image = np.ones((HEMISPHERE_RES, HEMISPHERE_RES, 3))
    peak = max(float(values.max()), 1e-12)
    image[inside] = _display(values / peak)
    ax.imshow(image, extent=(-1, 1, -1, 1))
    ax.plot(*np.array([np.cos(t := np.linspace(0, 2 * np.pi, 200)), np.sin(t)]), color="0.5", lw=0.8)
    ax.plot([wi[0]], [wi[1]], marker="x", color="w", ms=8)
    ax.annotate("wi", (wi[0], wi[1]), textcoords="offset points", xytext=(4, 4), fontsize=8, color="w")
    ax.set_title(f"f cos(theta_o) over the hemisphere, sRGB (peak {peak:.3g})", fontsize=10)
    ax.set_xlabel("x")
    ax.set_ylabel("y")


def save_figure(fig, path: str) -> None:
    """Write a matplotlib figure as PNG, atomically."""
    write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"), suffix=".png.tmp")
