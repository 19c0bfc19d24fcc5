"""`bsdflab table`: inspect and plot BSDF table files (OpenEXR, docs/table_format.md)."""
from __future__ import annotations

import argparse
import json
import os

import numpy as np


def register(sub) -> None:
    p = sub.add_parser("table", help="inspect and plot BSDF table files (.exr)",
                       description="Inspect and plot tabulated BSDFs stored as OpenEXR table "
                                   "files (format: docs/table_format.md). Every file is verified "
                                   "(format version, shapes, content hash) before use.")
    actions = p.add_subparsers(dest="action", metavar="ACTION", required=True)

    info = actions.add_parser("info", help="print a table file's metadata and accuracy",
                              description="Print the model, grid, lobes, channels, units, samples "
                                          "per cell (PFMC) or the solver's settings (adding-doubling), "
                                          "the target, the achieved error (95th percentile, max, RMS) "
                                          "and whether the target was met, and the writer's version of "
                                          "a table file, after verifying it.")
    info.add_argument("file", metavar="FILE", help="table file (.exr)")

    plot = actions.add_parser("plot", help="plot a table's in-plane slices and error map (PNG)",
                              description="Plot f(theta_o) in the plane of incidence (phi = 0 and "
                                          "phi = 180 deg) at a few theta_i per channel with error "
                                          "bands (PFMC: +-2 standard errors; adding-doubling: +- the "
                                          "solver's deterministic bound), and that relative error "
                                          "over theta_o x phi at one theta_i. A layered model's "
                                          "table holds its scattered part: the top's own reflection, "
                                          "the specular peak included, is added at lookup.")
    plot.add_argument("file", metavar="FILE", help="table file (.exr)")
    plot.add_argument("--out", default="table.png", help="output PNG path (default table.png)")
    plot.add_argument("--thickness-index", type=int, default=0,
                      help="which film-thickness node to plot, for tables with several (default 0)")
    export = actions.add_parser("export", help="write a table as a measured-BSDF file (RGL .bsdf)",
                                description="Resample an isotropic table's reflection into an RGL "
                                            ".bsdf file (Dupuy & Jakob 2018), which Mitsuba 3's "
                                            "'measured' plugin and pbrt-v4's 'measured' material read "
                                            "natively (docs/measured.md). Prints the measured "
                                            "resampling error and the bound the file is tested against.")
    export.add_argument("file", metavar="FILE", help="table file (.exr)")
    export.add_argument("--format", choices=["rgl"], default="rgl", help="output format (rgl)")
    export.add_argument("--out", required=True, help="output path (.bsdf)")
    export.add_argument("--theta-i", type=int, default=16, help="incident elevations, 2-90 (default 16)")
    export.add_argument("--resolution", type=int, default=32,
                        help="nodes per side of the value grids, 4-256 (default 32)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    return {"info": run_info, "plot": run_plot, "export": run_export}[args.action](args)


def run_export(args: argparse.Namespace) -> int:
    from bsdflab.measured.rgl import export_table

    report = export_table(args.file, args.out, n_theta_i=args.theta_i, resolution=args.resolution)
    print(f"wrote         {args.out} ({report.bytes} bytes, {report.seconds:.1f} s)")
    print(f"error         {report.summary()}")
    return 0


def run_plot(args: argparse.Namespace) -> int:
    from bsdflab.plots.table import table_figure
    from bsdflab.tables.file_format import read_table

    table = read_table(args.file)
    if not 0 <= args.thickness_index < table.n_thickness:
        raise ValueError(f"--thickness-index must be in [0, {table.n_thickness - 1}] for this table, "
                         f"got {args.thickness_index}")
    shows = table_figure(table, args.out, thickness_index=args.thickness_index,
                         source=f"{os.path.basename(args.file)}: ")
    print(f"wrote         {args.out}")
    print(f"shows         {shows}")
    return 0


def run_info(args: argparse.Namespace) -> int:
    from bsdflab.tables.file_format import read_attributes, read_table
    from bsdflab.tables.summary import BOUND, describe_accuracy

    table = read_table(args.file)  # verifies everything, the hash included
    attributes = read_attributes(args.file)
    g = table.grid
    meta = dict(table.meta)
    preset = meta.pop("preset", None)
    step = np.degrees(0.5 * np.pi / np.array([g.n_theta_i, g.n_theta_o]))
    accuracy, accuracy_lines = describe_accuracy(table)
    samples = table.samples
    if accuracy["kind"] == BOUND:  # one solve, no walks: no sample counts to show
        effort = ("method", f"adding-doubling (deterministic; stored errors are the solver's bound, "
                            f"{meta.get('solver', {}).get('nodes', '?')} nodes per panel, "
                            f"{meta.get('solver', {}).get('orders', '?')} Fourier orders)")
        for k in ("min_samples", "max_samples"):  # written by older versions, meaningless here
            meta.pop(k, None)
    else:
        effort = ("samples", f"min {samples.min()}  median {np.median(samples):g}  max {samples.max()}"
                             "  (walks per cell)")
    lines = [
        ("file", args.file),
        ("model", str(table.model.get("type", "?")) + (f" (preset {preset})" if preset else "")),
        ("grid", f"theta_i {g.n_theta_i} x theta_o {g.n_theta_o} cell centres "
                 f"({step[0]:.4g} / {step[1]:.4g} deg steps over 0-90), "
                 f"phi {g.n_phi} nodes over 0-180 deg ({180 / (g.n_phi - 1):.4g} deg steps)"),
        ("thickness", ", ".join(f"{t:g}" for t in g.thickness_nm) + " nm" if g.thickness_nm
         else "the model's own (no thickness axis)"),
        ("lobes", ", ".join(table.lobes)),
        ("sides", table.sides()),
        ("channels", _channels(table, attributes)),
        ("split direct", ("yes: the top interface's reflection is evaluated exactly at lookup"
                          + (" (from below: the base's)" if table.two_sided else ""))
         if table.split_direct else "no: the table holds the whole non-delta BSDF"),
        ("units", ", ".join(f"{k} {v}" for k, v in json.loads(attributes["bsdflab.units"]).items())),
        effort,
        *accuracy_lines,
        ("written by", f"bsdflab {attributes.get('bsdflab.version', '?')}, "
                       f"table format version {attributes.get('bsdflab.format_version', '?')}"),
        ("content hash", f"OK ({attributes['bsdflab.content_hash'][:16]}...)"),
        ("signature", _signature(attributes)),
    ]
    lines += [(f"meta {k}", _compact(v)) for k, v in sorted(meta.items())]
    width = max(13, *(len(label) + 1 for label, _ in lines))
    for label, text in lines:
        print(f"{label:<{width}} {text}")
    return 0


def _signature(attributes) -> str:
    from bsdflab.tables import signing

    if "bsdflab.signature" not in attributes:
        return "none" + (" (refused: a key is set)" if signing.resolve_key(None) else "")
    if signing.resolve_key(None) is None:
        return f"present, not verified (set {signing.ENV_VAR} to verify)"
    return "verified with the configured key"


def _channels(table, attributes) -> str:
    space = attributes.get("bsdflab.colour_space", "")
    if not table.spectral:
        return f"R, G, B ({space})"
    names = table.channels
    shown = ", ".join(names) if len(names) <= 8 else f"{names[0]}, {names[1]}, ..., {names[-1]}"
    return f"{len(names)} wavelengths: {shown} ({space})"


def _compact(value) -> str:
    text = repr(value) if not isinstance(value, str) else value
    return text if len(text) <= 100 else text[:97] + "..."
