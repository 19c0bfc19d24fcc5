"""Command-line options that describe a material, turned into a BSDF dict."""
from __future__ import annotations

import argparse
import json

from bsdflab.bsdfs import BSDF, from_dict

MATERIALS = ("diffuse", "conductor", "dielectric")


def add_material_options(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("material")
    g.add_argument("--material", choices=MATERIALS, default="diffuse",
                   help="basic material (default: diffuse)")
    g.add_argument("--reflectance", type=float, nargs="+", default=[0.5], metavar="R",
                   help="diffuse albedo: one value or linear-sRGB R G B in [0, 1] (default 0.5)")
    g.add_argument("--metal", default=None, help="conductor: named metal (Ag, Al, Au, Cu)")
    g.add_argument("--eta", type=float, default=None, help="conductor: real index (with --k)")
    g.add_argument("--k", type=float, default=None, help="conductor: extinction coefficient")
    g.add_argument("--int-ior", type=float, default=1.5046, help="dielectric: interior index")
    g.add_argument("--ext-ior", type=float, default=1.000277, help="exterior index")
    g.add_argument("--preset", default=None, metavar="NAME",
                   help="a named preset (bsdflab.presets.PRESETS, e.g. xenopeltis); overrides --material")
    g.add_argument("--json", default=None, metavar="DICT",
                   help="the material as a JSON dict (BSDF.to_dict form); overrides the rest")


def material_from_args(args: argparse.Namespace) -> BSDF:
    if args.json is not None:
        try:
            d = json.loads(args.json)
        except json.JSONDecodeError as e:
            raise ValueError(f"--json is not valid JSON: {e}") from None
        return from_dict(d)
    if args.preset is not None:
        from bsdflab.presets import preset

        return preset(args.preset)
    if args.material == "diffuse":
        r = args.reflectance[0] if len(args.reflectance) == 1 else args.reflectance
        if len(args.reflectance) not in (1, 3):
            raise ValueError("--reflectance takes one value or three (R G B)")
        return from_dict({"type": "diffuse", "reflectance": r})
    if args.material == "conductor":
        if args.metal is not None:
            return from_dict({"type": "conductor", "material": args.metal, "ext_ior": args.ext_ior})
        if args.eta is not None or args.k is not None:
            return from_dict({"type": "conductor", "eta": args.eta if args.eta is not None else 1.0,
                              "k": args.k if args.k is not None else 0.0, "ext_ior": args.ext_ior})
        return from_dict({"type": "conductor", "ext_ior": args.ext_ior})
    return from_dict({"type": "dielectric", "int_ior": args.int_ior, "ext_ior": args.ext_ior})
