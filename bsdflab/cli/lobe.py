"""`bsdflab lobe`: plot a material's lobe and its reflectance vs incidence angle."""
from __future__ import annotations

import argparse

import numpy as np

from bsdflab.cli.materials import add_material_options, material_from_args
from bsdflab.util.args import real_scalar


def register(sub) -> None:
    p = sub.add_parser("lobe", help="plot a BSDF lobe (PNG) and print its albedo",
                       description="Plot the scattering lobe of a material in the plane of "
                                   "incidence, in linear sRGB (D65), and its albedo vs angle.")
    add_material_options(p)
    p.add_argument("--theta-i", type=float, default=30.0, help="incidence angle in degrees (default 30)")
    p.add_argument("--out", default="lobe.png", help="output PNG path (default lobe.png)")
    p.add_argument("--samples", type=int, default=200_000,
                   help="Monte Carlo samples for the albedo estimates (default 200000)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from bsdflab.plots.lobe import lobe_figure

    theta = real_scalar("--theta-i", args.theta_i, 0.0, 90.0, hi_open=True)
    if args.samples <= 0:
        raise ValueError("--samples must be > 0")
    bsdf = material_from_args(args)
    summary = lobe_figure(bsdf, np.radians(theta), args.out, samples=args.samples, seed=args.seed)
    name = args.preset or bsdf.to_dict()["type"]
    print(f"material      {name}")
    print(f"theta_i       {theta:g} deg")
    for name, rgb in summary.items():
        print(f"{name:<13} R {rgb[0]:.4f}  G {rgb[1]:.4f}  B {rgb[2]:.4f}")
    print(f"wrote         {args.out}")
    return 0
