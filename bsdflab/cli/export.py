"""`bsdflab export`: a material as OpenPBR (MaterialX), glTF, USD or Blender, fitted, with a report."""
from __future__ import annotations

import argparse
import json

FORMATS = ("openpbr", "gltf", "usd", "blender")


def register(sub) -> None:
    p = sub.add_parser(
        "export", help="export a material to OpenPBR/MaterialX, glTF, USD or Blender (fitted, with a report)",
        description="Fit the target standard's thin-film parameters to bsdflab's exact film (CIEDE2000 over "
                    "incidence angle and the ±15 % film-thickness spread), write the target's file and "
                    "<out>.report.json / <out>.report.png (the Delta E00 map, what was dropped). See docs/export.md.")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--preset", metavar="NAME", help="a named preset (e.g. xenopeltis)")
    src.add_argument("--json", metavar="MODEL", help="the material as a JSON dict (BSDF.to_dict form), or a "
                                                     "file holding one (a fit study's material.json)")
    src.add_argument("--table", metavar="T.exr", help="a table file: exports the model its header records")
    p.add_argument("--set", action="append", default=[], metavar="K=V",
                   help="a preset parameter (repeatable; value parsed as JSON, else a string)")
    p.add_argument("--format", required=True, metavar="F",
                   help="one of openpbr (.mtlx), gltf (.gltf + .bin or .glb), usd (.usda), "
                        "blender (.blend + .blend.py)")
    p.add_argument("--out", required=True, metavar="PATH", help="output file")
    p.add_argument("--substitute", action="store_true",
                   help="export a multilayer film stack as the single film that looks most like it "
                        "(fitted against the stack's exact reflectance; the report says so)")
    p.set_defaults(run=run)


def model_from_args(args: argparse.Namespace):
    if args.set and args.preset is None:
        raise ValueError("--set applies to --preset only")
    if args.preset is not None:
        from bsdflab.cli.key_values import key_values
        from bsdflab.requests import model_from_spec

        return model_from_spec({"preset": args.preset, "overrides": key_values(args.set, "--set")}).to_dict()
    if args.json is not None:
        text, where = args.json, "--json"
        if not text.lstrip().startswith("{"):   # a file (a fit study's material.json)
            try:
                with open(text, encoding="utf-8") as f:
                    text, where = f.read(), text
            except (OSError, UnicodeDecodeError) as e:
                raise ValueError(f"--json is neither a JSON dict nor a readable file: {e}") from None
        try:
            d = json.loads(text)
        except json.JSONDecodeError as e:
            raise ValueError(f"{where} is not valid JSON: {e}") from None
        from bsdflab.requests import model_from_spec

        return model_from_spec({"model": d}).to_dict()
    from bsdflab.tables.file_format import read_table

    return read_table(args.table).model


def run(args: argparse.Namespace) -> int:
    from bsdflab.cli.errors import check_writable
    from bsdflab.export import export

    check_writable(args.out, "--out")
    model = model_from_args(args)
    try:
        report = export(model, args.format, args.out, name=args.preset or "bsdflab", substitute=args.substitute)
    except RuntimeError as e:  # the real tool refused the file (MaterialX validate, bpy)
        raise ValueError(str(e)) from None
    p, e = report["parameters"], report["delta_e00"]
    print(f"target      {report['target']}")
    print(f"fitted      film {p['film_thickness_nm']['value']:.1f} nm, n {p['film_ior']['value']:.4f}; "
          f"base n {p['base_ior']['value']:.4f}; roughness {p['roughness']['value']:.3f}")
    print(f"Delta E00   median {e['median']:.2f}, max {e['max']:.2f}, >1 on {100 * e['share_above_1']:.0f} %, "
          f">2 on {100 * e['share_above_2']:.0f} % of angle x thickness")
    print(f"wrote       {', '.join(report['files'])}, {args.out}.report.json, {args.out}.report.png")
    return 0
