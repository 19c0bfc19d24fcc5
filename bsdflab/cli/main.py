"""`bsdflab` entry point: one subcommand per module in this package."""
from __future__ import annotations

import argparse
import sys

from bsdflab._version import __version__
from bsdflab.cli import export, fit, info, lobe, render, serve, table, tabulate, thinfilm, validate

COMMANDS = (render, lobe, thinfilm, tabulate, table, info, fit, serve)
COMMANDS += (validate, export)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bsdflab",
        description="Measure, tabulate, render and validate layered thin-film BSDFs.")
    parser.add_argument("--version", action="version", version=f"bsdflab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command in ``argv`` and return its exit status. As the program (``argv``
    None: the console script, ``python -m``) an interrupted command leaves at once,
    skipping the interpreter's teardown (bsdflab/cli/leave.py); with a list, as tests call
    it in-process, it returns 130."""
    from bsdflab.cli.errors import INTERRUPTED, run_command

    parser = build_parser()
    args = parser.parse_args(argv)
    status = run_command(args)
    if status == INTERRUPTED and argv is None:
        from bsdflab.cli.leave import leave

        leave(status)
    return status


if __name__ == "__main__":
    sys.exit(main())
