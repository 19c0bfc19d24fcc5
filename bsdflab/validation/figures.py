"""Matplotlib figures as base64 PNG for the self-contained report (Agg canvas, no pyplot)."""
from __future__ import annotations

import base64
import io


def new_figure(width: float = 9.0, height: float = 3.2, cols: int = 1, rows: int = 1):
    """(figure, axes) on an Agg canvas; axes is a list when cols * rows > 1."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, cols)
    if cols * rows > 1:
        axes = list(axes.ravel())
    return fig, axes


def to_base64_png(fig, dpi: int = 80) -> str:
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=dpi)
    return base64.b64encode(buf.getvalue()).decode("ascii")
