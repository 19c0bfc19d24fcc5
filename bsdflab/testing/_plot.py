"""PNG rendering of chi-square tables (matplotlib, Agg canvas; imported only when used)."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_observed_expected(observed: np.ndarray, expected: np.ndarray, path,
                           title: str = "") -> Path:
    """Three panels over (phi, cos theta): observed counts, expected counts and their
    difference, written to ``path`` as a PNG."""
    # Figure + FigureCanvasAgg instead of pyplot: no global backend switch, no GUI.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    out = Path(path)
    if out.suffix.lower() != ".png":
        raise ValueError(f"path must end in .png, got {str(path)!r}")
    difference = observed - expected
    limit = float(np.max(np.abs(difference))) or 1.0
    top = float(max(observed.max(), expected.max())) or 1.0
    extent = (-np.pi, np.pi, -1.0, 1.0)

    fig = Figure(figsize=(15, 4.8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)
    panels = (("observed (histogram)", observed, dict(vmin=0, vmax=top, cmap="viridis")),
              ("expected (integrated pdf)", expected, dict(vmin=0, vmax=top, cmap="viridis")),
              ("observed - expected", difference, dict(vmin=-limit, vmax=limit, cmap="coolwarm")))
    for ax, (name, table, style) in zip(axes, panels):
        image = ax.imshow(table, origin="lower", extent=extent, aspect="auto",
                          interpolation="nearest", **style)
        ax.set_title(name)
        ax.set_xlabel("phi (rad)")
        ax.set_ylabel("cos theta (< 0: below the surface)")
        fig.colorbar(image, ax=ax, fraction=0.046, pad=0.04)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    return out
