"""The scale-texture figure: which scale each point belongs to, and what it does to shading.

Panels over a patch of (u, v):
(a) scales, each in a colour drawn from its id, gaps black;
(b) the shading slope: hue = direction of the normal's lean, brightness = its size relative
    to dome + tan(tilt) (gaps black);
(c) the film-thickness factor per scale (gaps grey at 1).
"""
from __future__ import annotations

import numpy as np

from bsdflab.plots.lobe import save_figure
from bsdflab.render.textures import ScaleTexture

RESOLUTION = 400


def _id_colours(ids: np.ndarray) -> np.ndarray:
    """A stable pseudo-random colour per id: three bytes of the id, kept away from black."""
    channels = [((ids >> np.uint64(shift)) & np.uint64(0xFF)).astype(float) / 255 for shift in (8, 24, 40)]
    return 0.25 + 0.75 * np.stack(channels, axis=-1)


def scale_texture_figure(texture: ScaleTexture, path: str, u_range=(0.0, 1.0), v_range=(0.0, 1.0),
                         title: str = "") -> dict:
    """Write the figure to `path` (PNG, atomically) and return a summary.

    Returns
    -------
    dict
        "gap_fraction": fraction of the patch in gaps; "scales": distinct scale ids seen;
        "max_slope": the largest |slope| seen.
    """
    if not isinstance(texture, ScaleTexture):
        raise ValueError(f"texture must be a ScaleTexture, got {type(texture).__name__}")
    (u0, u1), (v0, v1) = (tuple(map(float, u_range)), tuple(map(float, v_range)))
    if not (np.isfinite([u0, u1, v0, v1]).all() and u1 > u0 and v1 > v0):
        raise ValueError(f"u_range and v_range must be finite (low, high) pairs, got {u_range}, {v_range}")
    u = np.linspace(u0, u1, RESOLUTION)
    v = np.linspace(v0, v1, RESOLUTION)
    # image rows are v (around the body), columns u (along it)
    r = texture.lookup(u[None, :], v[:, None])
    gap = r["gap"]

    scales = _id_colours(r["id"])
    scales[gap] = 0.0

    slope_u, slope_v = r["slope_u"], r["slope_v"]
    magnitude = np.hypot(slope_u, slope_v)
    bound = texture.dome + np.tan(np.radians(texture.tilt_deg))
    hue = (np.arctan2(-slope_v, -slope_u) / (2 * np.pi)) % 1.0  # the normal leans along -slope
    value = np.clip(magnitude / bound, 0, 1) if bound > 0 else np.zeros_like(magnitude)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import hsv_to_rgb

    slope_image = hsv_to_rgb(np.stack([hue, np.ones_like(hue), value], axis=-1))
    slope_image[gap] = 0.0

    extent = (u0, u1, v0, v1)
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.2), constrained_layout=True)
    axes[0].imshow(scales, origin="lower", extent=extent, aspect="auto", interpolation="nearest")
    axes[0].set_title(f"(a) scales by id, gaps black ({texture.gap:g} of the spacing)", fontsize=10)
    axes[1].imshow(slope_image, origin="lower", extent=extent, aspect="auto", interpolation="nearest")
    axes[1].set_title(f"(b) normal lean: hue = direction, brightness = |slope| / {bound:.3g}", fontsize=10)
    thickness = axes[2].imshow(r["thickness_factor"], origin="lower", extent=extent, aspect="auto",
                               interpolation="nearest", cmap="coolwarm",
                               vmin=1 - max(texture.thickness_jitter, 1e-3),
                               vmax=1 + max(texture.thickness_jitter, 1e-3))
    axes[2].set_title("(c) film thickness factor (gaps at 1)", fontsize=10)
    fig.colorbar(thickness, ax=axes[2], shrink=0.85)
    for ax in axes:
        ax.set_xlabel("u (along the body)")
        ax.set_ylabel("v (around the body)")
    fig.suptitle(title or f"hexagonal scales: {texture.scales_per_unit_u:g} rows per unit u, "
                          f"{texture.scales_around} around, jitter {texture.jitter:g}, seed {texture.seed}")
    save_figure(fig, path)
    plt.close(fig)
    return {"gap_fraction": float(gap.mean()), "scales": int(len(np.unique(r["id"]))),
            "max_slope": float(magnitude.max())}
