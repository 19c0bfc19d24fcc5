"""`bsdflab info`: versions, threads, and what the installation can do."""
from __future__ import annotations

import argparse


def register(sub) -> None:
    p = sub.add_parser("info", help="print versions and core settings",
                       description="Print bsdflab's version, the C++ core's thread count and the "
                                   "named metals shipped with the package.")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from bsdflab import _core
    from bsdflab._version import __version__
    from bsdflab.optics.metals import METALS, metal_provenance

    print(f"bsdflab       {__version__}")
    print(f"core threads  {_core.worker_count()}  (set BSDFLAB_THREADS to change)")
    for m in METALS:
        first = metal_provenance(m).splitlines()
        print(f"metal {m:<7} {first[1] if len(first) > 1 else first[0] if first else ''}")
    return 0
