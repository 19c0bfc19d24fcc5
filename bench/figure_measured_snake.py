"""README figure: the snake's table exported to RGL (.bsdf), rendered natively by Mitsuba 3's
``measured`` plugin beside bsdflab's path tracer reading the same file with bl.Measured.

    python bench/figure_measured_snake.py [--out docs/images/measured_snake.png] [--spp 256]
"""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="docs/images/measured_snake.png")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--grid", choices=["small", "default"], default="small",
                    help="small: the CI table (6 x 12 x 7, 5 %% error); default: 12 x 24 x 13, 2 %%")
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bsdflab.measured import export_table
    from bsdflab.presets import xenopeltis
    from bsdflab.reference.mitsuba_render import render_mitsuba
    from bsdflab.render import Camera, Environment, Material, Scene, Shape
    from bsdflab.render.build import resolve_bsdf
    from bsdflab.render.render import render

    folder = Path(tempfile.mkdtemp())
    grid, rel = (((6, 12, 7), 0.05) if args.grid == "small" else ((12, 24, 13), 0.02))
    table = resolve_bsdf({"type": "tabulated", "model": xenopeltis().to_dict(), "min_samples": 256,
                          "grid": {"n_theta_i": grid[0], "n_theta_o": grid[1], "n_phi": grid[2], "thickness_nm": []},
                          "rel_error": rel})
    path = folder / "snake.bsdf"
    report = export_table(table, path)
    print(report.summary(), f"{report.bytes} bytes")
    w, h = args.width, args.width * 3 // 4
    scene = Scene(Camera(origin=(0.0, 1.4, 3.2), target=(0.0, 1.0, 0.0), fov_deg=45, width=w, height=h),
                  (Shape({"type": "sphere", "center": [0, 1, 0], "subdivisions": 64}, "snake", name="ball"),),
                  {"snake": Material({"type": "measured", "path": str(path)})},
                  Environment("sky", scale=2.0), max_depth=4, rr_depth=3)
    ours = render(scene, spp=args.spp, seed=0, progress=False).mean
    theirs = render_mitsuba(scene, args.spp, seed=1)[0]
    white = np.percentile(np.concatenate([ours.ravel(), theirs.ravel()]), 99.5)
    show = lambda img: np.clip(np.clip(img / white, 0, 1) ** (1 / 2.2), 0, 1)
    fig, ax = plt.subplots(1, 2, figsize=(8, 3.2))
    for a, img, title in zip(ax, (ours, theirs), ("bsdflab (bl.Measured)", "Mitsuba 3 (native measured)")):
        a.imshow(show(img))
        a.set_title(title, fontsize=9)
        a.axis("off")
    fig.suptitle(f"Xenopeltis table ({grid[0]} x {grid[1]} x {grid[2]}) exported as RGL .bsdf; "
                 f"the same file in both renderers, {args.spp} spp", fontsize=9)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120, bbox_inches="tight")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
