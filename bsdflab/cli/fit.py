"""`bsdflab fit`: MCMC parameter-uncertainty studies from reflectance data.

    bsdflab fit data.csv --config fit.toml --out study/
    bsdflab fit simulate --config truth.toml --out data.csv
    bsdflab fit import FILE... --out data.csv   (bsdflab/cli/fit_import.py)
"""
from __future__ import annotations

import argparse
import os
import shlex
import sys

from bsdflab.cli import fit_import


def register(sub) -> None:
    p = sub.add_parser("fit", help="fit film/slab parameters to reflectance data with MCMC (emcee)",
                       description="Fit the thin-film + absorbing-slab + diffuse-base model to reflectance "
                                   "data (docs/fit_data.md) and write a study folder: posterior (netCDF), "
                                   "parameter table, corner plot, predictive bands, traces, appearance "
                                   "posterior, renders, posterior-mean material. 'bsdflab fit simulate "
                                   "--config truth.toml --out data.csv' writes synthetic data instead; "
                                   "'bsdflab fit import FILE... --out data.csv' reads instrument files "
                                   "(bsdflab fit import --help).")
    p.add_argument("data", metavar="DATA.csv|simulate",
                   help="data file to fit, or the word 'simulate' to make synthetic data")
    p.add_argument("--config", required=True, help="fit.toml (priors, sampler) or, with simulate, truth.toml")
    p.add_argument("--out", required=True, help="study folder (fit) or data file (simulate)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--strict", action="store_true",
                   help="exit with status 3 when the study raises a warning (the folder is still written)")
    p.set_defaults(run=run)
    fit_import.attach(p)


def run(args: argparse.Namespace) -> int:
    import os

    if args.data == "simulate":
        from bsdflab.fit.config import SimulationConfig
        from bsdflab.fit.simulate import simulate

        if not args.out.lower().endswith(".csv"):
            raise ValueError(f"--out must end in .csv, got {args.out!r}")
        if os.path.exists(args.out) and not args.overwrite:
            raise ValueError(f"--out {args.out} already exists (use --overwrite)")
        config = SimulationConfig.load(args.config)
        command = "bsdflab fit simulate --config " + shlex.quote(os.path.basename(args.config)) + \
                  " --out " + shlex.quote(os.path.basename(args.out))
        dataset, _ = simulate(config, command)
        dataset.write_csv(args.out)
        print(f"wrote {len(dataset)} synthetic rows to {args.out} (noise seed {config.seed})")
        return 0

    from bsdflab.fit.config import FitConfig, load_toml
    from bsdflab.fit.study import run_study

    if "structure" in load_toml(args.config):  # a structure fit (docs/fit.md, "Structures and instruments")
        return _run_stack(args)
    config = FitConfig.load(args.config)
    try:
        summary = run_study(args.data, config, args.out, progress=not args.quiet, overwrite=args.overwrite)
    except KeyboardInterrupt:
        print(f"\nbsdflab fit: interrupted; nothing was written to {args.out}", file=sys.stderr)
        return 130
    print(summary["stop_reason"])
    if summary["sampler"] == "nested":
        print(f"evidence ln Z = {summary['log_evidence']:.3f} +- {summary['log_evidence_error']:.3f}; "
              f"ESS (Kish) {summary['ess_kish']:.0f}")
    else:
        print(f"acceptance fraction {summary['acceptance_fraction']['mean']:.3f}; "
              f"min ESS {summary['ess_tau_min']:.0f} ({summary['ess_per_second']:.1f}/s)")
    with open(os.path.join(args.out, "parameters.md"), encoding="utf-8") as f:
        print(f.read())
    print(summary["appearance"]["statement"])
    return _report(summary, args)


def _report(summary: dict, args: argparse.Namespace) -> int:
    """The predictive checks' line, the folder, and the warnings block on stderr; status 3
    under --strict when there are warnings."""
    checks = summary["predictive_checks"]["series"]
    worst = min(checks[1:] or checks, key=lambda c: c["p_value"])
    print(f"posterior predictive checks (alpha {summary['predictive_checks']['alpha']:g}): all rows p = "
          f"{checks[0]['p_value']:.3g} (chi2/n {checks[0]['chi2_per_row']:.2f}); lowest series {worst['series']} "
          f"p = {worst['p_value']:.3g}; {sum(c['flagged'] for c in checks)} of {len(checks)} fail")
    print(f"wrote {args.out}")
    if summary["warnings"]:
        from bsdflab.fit.alerts import Alert, render_block

        sys.stdout.flush()
        sys.stderr.write(render_block([Alert(**w) for w in summary["warnings"]]))
        if args.strict:
            return 3
    return 0


def _run_stack(args: argparse.Namespace) -> int:
    """A structure + instrument fit; DATA is '-' when the config lists its [[dataset]] files."""
    from bsdflab.fit.full_stack_config import load_structure_config
    from bsdflab.fit.stack_study import run_stack_study

    config = load_structure_config(args.config)   # the smooth stack's, or the full model's
    try:
        summary = run_stack_study(config, args.out, None if args.data == "-" else args.data,
                                  progress=not args.quiet, overwrite=args.overwrite)
    except KeyboardInterrupt:
        print(f"\nbsdflab fit: interrupted; nothing was written to {args.out}", file=sys.stderr)
        return 130
    print(summary["stop_reason"])
    with open(os.path.join(args.out, "parameters.md"), encoding="utf-8") as f:
        print(f.read())
    return _report(summary, args)
