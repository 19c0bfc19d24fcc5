"""`bsdflab fit import`: instrument and spreadsheet files -> the fit's long dataset.

    bsdflab fit import angles.csv --out data.csv                 # sidecar angles.csv.toml
    bsdflab fit import scan_*.ProcSpec --geometry specular --units percent --sigma-absolute 0.5 --out data.csv

Formats, sidecar keys and the units rule: docs/fit_data.md ("Importing instrument files").
"""
from __future__ import annotations

import argparse
import os


def build_parser(prog: str) -> argparse.ArgumentParser:
    from bsdflab.fit.readers.base import READERS

    p = argparse.ArgumentParser(
        prog=prog,
        description="Read instrument exports or a wide spreadsheet (a wavelength column, one column per angle "
                    "or sample) and write the fit's long dataset (docs/fit_data.md). What the files do not say "
                    "(geometry, angles, units, reference standard, sigma) comes from a TOML sidecar "
                    "(<file>.toml or --sidecar) or the options below, which override it.")
    p.add_argument("files", nargs="+", metavar="FILE", help="files to read (one format; several: e.g. one per angle, "
                                                            "replicates averaged)")
    p.add_argument("--out", required=True, help="the dataset to write (.csv)")
    p.add_argument("--sidecar", help="TOML sidecar (default: <first file>.toml, or <stem>.toml, if present)")
    p.add_argument("--format", choices=READERS.names(), help="the files' format (default: from suffix and contents)")
    p.add_argument("--geometry", choices=("specular", "diffuse", "total", "brdf"))
    p.add_argument("--angles", help="angles of incidence, one per column (wide file) or per file, comma-separated")
    p.add_argument("--angle", type=float, help="one angle of incidence (deg) for every curve")
    p.add_argument("--angle-out", type=float, help="detector polar angle (deg; diffuse and brdf)")
    p.add_argument("--phi", type=float, help="detector azimuth (deg; brdf)")
    p.add_argument("--units", choices=("percent", "fraction"), help="units of the values (percent is converted)")
    p.add_argument("--series", help="series name for every row")
    p.add_argument("--wavelengths", help="grid to resample onto: START:STOP:STEP or a comma list (nm)")
    p.add_argument("--sigma-absolute", type=float, help="absolute sigma, in the files' units")
    p.add_argument("--sigma-relative", type=float, help="relative sigma (fraction of the value)")
    p.add_argument("--reference", type=float, metavar="R",
                   help="the white standard's nominal reflectance (a fraction), values are relative to it")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.set_defaults(run=run, command="fit import")
    return p


def attach(fit_parser: argparse.ArgumentParser) -> None:
    """Let the `fit` parser hand `fit import ...` to this command's parser (its first
    positional is a data file or the word `simulate`, so `import` cannot be a subparser)."""
    base = type(fit_parser)

    class WithImport(base):
        def parse_known_args(self, args=None, namespace=None):
            if args and args[0] == "import":
                return build_parser(self.prog + " import").parse_known_args(args[1:], namespace)
            return super().parse_known_args(args, namespace)

    fit_parser.__class__ = WithImport


def run(args: argparse.Namespace) -> int:
    from bsdflab.fit.readers import default_sidecar, import_files, load_spec
    from bsdflab.fit.readers.sidecar import ImportSpec, Reference, float_option, parse_grid_option

    if not args.out.lower().endswith(".csv"):
        raise ValueError(f"--out must end in .csv, got {args.out!r}")
    if os.path.exists(args.out) and not args.overwrite:
        raise ValueError(f"--out {args.out} already exists (use --overwrite)")
    sidecar = args.sidecar or default_sidecar(args.files[0])
    spec = load_spec(sidecar) if sidecar else ImportSpec()
    for option, value in (("--angle", args.angle), ("--angle-out", args.angle_out), ("--phi", args.phi),
                          ("--sigma-absolute", args.sigma_absolute), ("--sigma-relative", args.sigma_relative),
                          ("--reference", args.reference)):
        if value is not None:
            float_option(option, str(value))
            if option.startswith("--sigma") and value < 0:
                raise ValueError(f"{option} must be >= 0, got {value:g}")
            if option == "--reference" and not 0 < value <= 1.5:
                raise ValueError(f"--reference is the standard's reflectance as a fraction (e.g. 0.99), got {value:g}")
    spec = spec.with_options(
        format=args.format, geometry=args.geometry, units=args.units, angle_deg=args.angle,
        angle_out_deg=args.angle_out, phi_deg=args.phi, series=args.series,
        angles_deg=tuple(float_option("--angles", a) for a in args.angles.split(",")) if args.angles else None,
        wavelengths=parse_grid_option(args.wavelengths) if args.wavelengths else None,
        sigma_absolute=args.sigma_absolute, sigma_relative=args.sigma_relative,
        reference=Reference(reflectance=args.reference) if args.reference is not None else None)
    dataset, notes = import_files(args.files, spec)
    dataset.write_csv(args.out)
    for note in notes:
        print(note)
    print(f"wrote {len(dataset)} rows to {args.out}" + (f" (sidecar {sidecar})" if sidecar else ""))
    return 0
