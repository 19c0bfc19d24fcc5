"""The diagnostic figure of an image z-test: both images and the z map (matplotlib, Agg)."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def _display(image: np.ndarray, white: float) -> np.ndarray:
    rgb = image if image.shape[2] == 3 else np.repeat(image[..., :1], 3, axis=2)
    return np.clip(np.clip(rgb, 0, None) / white, 0, 1) ** (1 / 2.2)


def z_test_figure(result, path, title: str, labels: tuple[str, str]) -> Path:
    """Write the PNG of an ``ImageTestResult`` to ``path`` (atomically) and return it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from bsdflab.plots.lobe import save_figure

    out = Path(path)
    if out.suffix.lower() != ".png":
        raise ValueError(f"path must end in .png, got {str(path)!r}")
    both = np.concatenate([result.mean_a.ravel(), result.mean_b.ravel()])
    both = both[np.isfinite(both)]
    white = float(np.percentile(both, 99)) if both.size else 1.0
    white = white if white > 0 else 1.0

    z = np.nan_to_num(result.z, nan=np.inf)
    strongest = np.take_along_axis(z, np.argmax(np.abs(z), axis=2)[..., None], axis=2)[..., 0]
    critical = float(np.sqrt(2.0) * _erfcinv(result.level))
    limit = max(critical, float(np.max(np.abs(strongest[np.isfinite(strongest)]), initial=0.0)))
    rejected = np.any(result.p < result.level, axis=2) | np.any(result.p == 0, axis=2)

    fig = Figure(figsize=(15, 4.4))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)
    axes[0].imshow(_display(result.mean_a, white), interpolation="nearest")
    axes[0].set_title(labels[0])
    axes[1].imshow(_display(result.mean_b, white), interpolation="nearest")
    axes[1].set_title(labels[1])
    im = axes[2].imshow(np.clip(strongest, -limit, limit), cmap="coolwarm", vmin=-limit, vmax=limit,
                        interpolation="nearest")
    rows, cols = np.nonzero(rejected)
    axes[2].scatter(cols, rows, s=60, facecolors="none", edgecolors="k", linewidths=1.0)
    axes[2].set_title(f"z (largest |z| channel); |z| > {critical:.2f} rejected (circled)")
    fig.colorbar(im, ax=axes[2], fraction=0.046, pad=0.04)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(title or result.summary(), fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, str(out))
    return out


def _erfcinv(p: float) -> float:
    from scipy.special import erfcinv

    return float(erfcinv(p))
