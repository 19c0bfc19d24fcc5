"""A labelled grid of rendered images (the appearance grid and ablation rows of Padrón-Griffe et al. 2023)."""
from __future__ import annotations

import math

import numpy as np


def mosaic(images: list[np.ndarray], columns: int, gap: int = 4) -> np.ndarray:
    """Linear images of one size tiled row by row with `gap` black pixels between them."""
    h, w, _ = images[0].shape
    if any(im.shape != images[0].shape for im in images):
        raise ValueError("contact sheet images must all have the same size")
    rows = math.ceil(len(images) / columns)
    out = np.zeros((rows * h + (rows - 1) * gap, columns * w + (columns - 1) * gap, 3), np.float32)
    for k, im in enumerate(images):
        r, c = divmod(k, columns)
        out[r * (h + gap):r * (h + gap) + h, c * (w + gap):c * (w + gap) + w] = im
    return out


def contact_sheet(items: list[tuple[str, np.ndarray]], path: str, exposure: float = 0.0,
                  title: str = "", columns: int | None = None) -> np.ndarray:
    """Write a PNG of the tone-mapped images with their labels; return the linear mosaic."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bsdflab.plots.lobe import save_figure
    from bsdflab.render.image_io import tone_map

    columns = columns or min(len(items), 3)
    rows = math.ceil(len(items) / columns)
    h, w, _ = items[0][1].shape
    fig, axes = plt.subplots(rows, columns, figsize=(columns * 3.2, rows * 3.2 * h / w + 0.4), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (label, image) in zip(axes.ravel(), items):
        ax.imshow(tone_map(image, exposure))
        ax.set_title(label, fontsize=9)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
    return mosaic([im for _, im in items], columns)
