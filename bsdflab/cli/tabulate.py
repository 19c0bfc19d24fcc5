"""`bsdflab tabulate`: measure a material into a table file (or fetch it from the cache)."""
from __future__ import annotations

import argparse
import sys

from bsdflab.cli.cluster_options import add_cluster_options, client_from_args
from bsdflab.cli.materials import add_material_options, material_from_args
from bsdflab.tables.deterministic import TABLE_NODES
from bsdflab.tables.request import CHOICES, DEFAULT_REL_ERROR
from bsdflab.tables.stages import DEFAULT_MAX_SAMPLES, DEFAULT_MIN_SAMPLES


def register(sub) -> None:
    p = sub.add_parser("tabulate", help="tabulate a BSDF into an OpenEXR table file",
                       description="Measure a material on a (theta_i, theta_o, phi[, film thickness]) "
                                   "grid, adaptively to a target relative error, and write a "
                                   "self-describing OpenEXR table (see docs/table_format.md).")
    add_material_options(p)
    p.add_argument("--out", default=None, help="output .exr path (default: only the cache)")
    p.add_argument("--rel-error", type=float, default=DEFAULT_REL_ERROR,
                   help=f"target: the 95th percentile over the cells of each cell's relative error "
                        f"(default {DEFAULT_REL_ERROR:g}; docs/table_format.md, 'Target met')")
    p.add_argument("--theta-i", type=int, default=12, dest="n_theta_i", help="incidence nodes (default 12)")
    p.add_argument("--theta-o", type=int, default=24, dest="n_theta_o", help="outgoing nodes (default 24)")
    p.add_argument("--phi", type=int, default=13, dest="n_phi", help="azimuth nodes over [0, pi] (default 13)")
    p.add_argument("--thickness", type=float, nargs="*", default=(), metavar="NM",
                   help="film-thickness nodes in nm (default: the model's own thickness only)")
    p.add_argument("--wavelengths", type=float, nargs="*", default=None, metavar="NM",
                   help="store these wavelengths instead of linear sRGB")
    p.add_argument("--min-samples", type=int, default=DEFAULT_MIN_SAMPLES,
                   help=f"pfmc: walks per cell in the first pass (default {DEFAULT_MIN_SAMPLES}; fewer leave "
                        "the stated errors too small for tail-heavy stacks, docs/coverage.md)")
    p.add_argument("--max-samples", type=int, default=DEFAULT_MAX_SAMPLES,
                   help=f"pfmc: cap on walks per cell (default {DEFAULT_MAX_SAMPLES})")
    p.add_argument("--seed", type=int, default=0, help="pfmc: random seed (default 0)")
    p.add_argument("--method", choices=CHOICES, default="auto",
                   help="auto (default): adding-doubling wherever the solver covers the model (reflecting "
                        "layered stacks, and transmissive ones with a smooth top over a smooth base, "
                        "tabulated on both sides: docs/solvers.md), else pfmc; pfmc (Monte Carlo) or adding-doubling "
                        "(deterministic) to choose; each is cached under its own key")
    p.add_argument("--nodes", type=int, default=None,
                   help=f"adding-doubling: Gauss-Legendre nodes per cosine panel, 4-256 (default {TABLE_NODES}); "
                        "more nodes shrink the error bound")
    p.add_argument("--orders", type=int, default=None,
                   help="adding-doubling: Fourier orders in azimuth, 1-4096 (default: automatic)")
    p.add_argument("--no-cache", action="store_true", help="always tabulate; do not read or fill the cache")
    p.add_argument("--cache-dir", default=None, help="cache folder (default: $BSDFLAB_CACHE_DIR or the user cache)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_cluster_options(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from bsdflab.cli.errors import check_writable
    from bsdflab.tables import TableGrid, TableRequest, get
    from bsdflab.util import runners

    if args.out is not None:
        check_writable(args.out, "--out")  # before the tabulation, not after it
    if args.no_cache and args.out is None:
        raise ValueError("--no-cache needs --out")
    grid = TableGrid(args.n_theta_i, args.n_theta_o, args.n_phi, tuple(args.thickness))
    request = TableRequest.make(material_from_args(args), grid, args.rel_error, args.wavelengths or None,
                                args.method, args.min_samples, args.max_samples, args.seed, args.nodes,
                                args.orders)
    with client_from_args(args) as client:  # connected (or refused) before any work
        runner = runners.resolve(None, client)
        fetched = get(request, cache=False if args.no_cache else args.cache_dir, runner=runner,
                      progress=not args.quiet)
    return _report(args, request, fetched)


def _report(args, request, fetched) -> int:
    import shutil

    from bsdflab.tables import write_table
    from bsdflab.tables.summary import describe_accuracy

    table, path, hit = fetched
    if args.out is not None:
        if path is not None and hit:
            from bsdflab.util.files import write_atomically

            write_atomically(args.out, lambda tmp: shutil.copyfile(path, tmp), suffix=".tmp.exr")
        else:
            write_table(args.out, table)
    grid, m = request.grid, table.meta
    print(f"table         {args.out or path}")
    print(f"from cache    {'yes' if hit else 'no'}" + (f" ({path})" if path else ""))
    print(f"method        {request.method} ({request.method_note})")
    print(f"grid          {grid.n_theta_i} x {grid.n_theta_o} x {grid.n_phi}, lobes {', '.join(table.lobes)}, "
          f"thickness nodes {list(grid.thickness_nm) or 'model default'}")
    print(f"parts         {', '.join(table.lobes)}: light {table.sides()}")
    accuracy, lines = describe_accuracy(table)
    for label, text in lines:
        print(f"{label:<13} {text}")
    print(f"time          {m.get('seconds', 0):.1f} s on {m.get('threads', '?')} threads")
    if not accuracy["target_met"]:
        print(f"bsdflab tabulate: warning: {accuracy['advice']}", file=sys.stderr)
    return 0
