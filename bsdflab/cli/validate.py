"""`bsdflab validate`: run the validation registry and write an HTML + JSON report."""
from __future__ import annotations

import argparse
import runpy
import sys


def register(sub) -> None:
    p = sub.add_parser("validate", help="run the validation checks and write a report",
                       description="Run bsdflab's validation checks (the same registry the test suite "
                                   "runs) and write OUT/index.html (self-contained) and OUT/results.json. "
                                   "Exit status 1 when a check fails.")
    p.add_argument("--level", choices=("quick", "standard", "full"), default="quick",
                   help="effort: quick (CI, minutes on 2 cores), standard, full (long studies)")
    p.add_argument("--only", metavar="PATTERN", help="only checks whose name matches this glob or contains it")
    p.add_argument("--family", action="append", default=None, metavar="NAME",
                   help="only checks of this family (repeatable; --list shows them)")
    p.add_argument("--out", help="folder for index.html and results.json (needed unless --list)")
    p.add_argument("--plugin", action="append", default=[], metavar="FILE.py",
                   help="a Python file whose checks() returns more Check objects (e.g. your own BSDF "
                        "through Check.with_model); repeatable")
    p.add_argument("--no-benchmarks", action="store_true", help="skip the benchmarks at standard / full")
    p.add_argument("--list", action="store_true", help="list the families and checks and exit")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(run=run)


def _plugin_checks(paths):
    found = []
    for path in paths:
        namespace = runpy.run_path(path)
        if not callable(namespace.get("checks")):
            raise ValueError(f"plugin {path!r} must define checks() returning a list of Check")
        found.extend(namespace["checks"]())
    return found


def run(args: argparse.Namespace) -> int:
    from bsdflab.validation import REGISTRY, load_checks, validate
    from bsdflab.validation.job import normalise_families

    load_checks()
    families = normalise_families(args.family)
    checks = REGISTRY.select(args.only, families) + [
        c for c in _plugin_checks(args.plugin)
        if (not args.only or args.only in c.name or c.name == args.only) and (families is None or c.family in families)]
    if args.list:
        print("families: " + ", ".join(f"{f} ({n})" for f, n in REGISTRY.families().items()
                                       if families is None or f in families))
        for c in checks:
            print(f"{c.name:60s} {c.family:9s} {c.title}")
        return 0
    if args.out is None:
        raise ValueError("--out is required: the folder for index.html and results.json")
    if not checks:
        raise ValueError(f"--only {args.only!r} (families {args.family or 'all'}) matches no check "
                         "(see bsdflab validate --list)")
    doc = validate(args.out, level=args.level, only=args.only, checks=checks, progress=not args.quiet,
                   benchmarks=False if args.no_benchmarks else None, argv=["bsdflab", *sys.argv[1:]])
    s = doc["summary"]
    print(f"bsdflab validate ({args.level}): {s['pass']} pass, {s['fail']} fail, {s['error']} error, "
          f"{s['skipped']} skipped, {s['study']} studies in {doc['duration_s']:.0f} s -> {args.out}/index.html")
    for c in doc["checks"]:
        if c["status"] in ("fail", "error"):
            print(f"  {c['status'].upper()}: {c['name']}: {c['message'].strip().splitlines()[-1][:200]}")
    return doc["exit_status"]
