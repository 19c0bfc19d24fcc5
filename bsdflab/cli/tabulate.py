"""`bsdflab tabulate`: measure a material into a table file (or fetch it from the cache)."""
from __future__ import annotations

import argparse
import sys

from bsdflab.cli.cluster_options import add_cluster_options, client_from_args
from bsdflab.cli.materials import add_material_options, material_from_args


def register(sub) -> None:
    p = sub.add_parser("tabulate", help="tabulate a BSDF into an OpenEXR table file",
                       description="Measure a material on a (theta_i, theta_o, phi[, film thickness]) "
                                   "grid, adaptively to a target relative error, and write a "
                                   "self-describing OpenEXR table (see docs/table_format.md).")
    add_material_options(p)
    p.add_argument("--out", default=None, help="output .exr path (default: only the cache)")
    p.add_argument("--rel-error", type=float, default=0.01,
                   help="target relative standard error per cell (default 0.01)")
    p.add_argument("--theta-i", type=int, default=12, dest="n_theta_i", help="incidence nodes (default 12)")
    p.add_argument("--theta-o", type=int, default=24, dest="n_theta_o", help="outgoing nodes (default 24)")
    p.add_argument("--phi", type=int, default=13, dest="n_phi", help="azimuth nodes over [0, pi] (default 13)")
    p.add_argument("--thickness", type=float, nargs="*", default=(), metavar="NM",
                   help="film-thickness nodes in nm (default: the model's own thickness only)")
    p.add_argument("--wavelengths", type=float, nargs="*", default=None, metavar="NM",
                   help="store these wavelengths instead of linear sRGB")
    p.add_argument("--min-samples", type=int, default=512, help="walks per cell in the first pass (default 512)")
    p.add_argument("--max-samples", type=int, default=65536, help="cap on walks per cell (default 65536)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--method", choices=("pfmc", "adding-doubling"), default="pfmc",
                   help="pfmc (Monte Carlo, default) or adding-doubling (deterministic, layered "
                        "reflectors, docs/solvers.md; cached under its own key)")
    p.add_argument("--no-cache", action="store_true", help="always tabulate; do not read or fill the cache")
    p.add_argument("--cache-dir", default=None, help="cache folder (default: $BSDFLAB_CACHE_DIR or the user cache)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_cluster_options(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from bsdflab.cli.errors import check_writable
    from bsdflab.tables import TableGrid, tabulate
    from bsdflab.tables.data import check_table_memory

    if args.out is not None:
        check_writable(args.out, "--out")  # before the tabulation, not after it
    model = material_from_args(args)
    grid = TableGrid(args.n_theta_i, args.n_theta_o, args.n_phi, tuple(args.thickness))
    wavelengths = args.wavelengths if args.wavelengths else None
    check_table_memory(grid, 3 if wavelengths is None else len(wavelengths))
    channels = "rgb" if wavelengths is None else [float(w) for w in wavelengths]

    with client_from_args(args) as client:  # connected (or refused) before any work
        def make():
            return tabulate(model, grid, rel_error=args.rel_error, wavelengths=wavelengths,
                            min_samples=args.min_samples, max_samples=args.max_samples,
                            seed=args.seed, progress=not args.quiet, client=client, method=args.method)

        return _tabulate(args, model, grid, channels, make)


def _tabulate(args, model, grid, channels, make) -> int:
    import shutil

    from bsdflab.tables import cached_table, write_table

    if args.no_cache:
        if args.out is None:
            raise ValueError("--no-cache needs --out")
        table, path, hit = make(), None, False
    else:
        table, path, hit = cached_table(model.to_dict(), grid, args.rel_error, channels, make,
                                        directory=args.cache_dir, min_samples=args.min_samples,
                                        max_samples=args.max_samples, seed=args.seed, method=args.method)
    if args.out is not None:
        if path is not None and hit:
            from bsdflab.util.files import write_atomically

            write_atomically(args.out, lambda tmp: shutil.copyfile(path, tmp), suffix=".tmp.exr")
        else:
            write_table(args.out, table)
    m = table.meta
    print(f"table         {args.out or path}")
    print(f"from cache    {'yes' if hit else 'no'}" + (f" ({path})" if path else ""))
    print(f"grid          {grid.n_theta_i} x {grid.n_theta_o} x {grid.n_phi}, lobes {', '.join(table.lobes)}, "
          f"thickness nodes {list(grid.thickness_nm) or 'model default'}")
    print(f"rel. error    target {table.rel_error_target:g}; achieved RMS {m.get('rel_error_rms', 0):.4g}, "
          f"95 % {m.get('rel_error_p95', 0):.4g}, max {m.get('rel_error_max', 0):.4g}")
    print(f"time          {m.get('seconds', 0):.1f} s on {m.get('threads', '?')} threads")
    accuracy = table.accuracy()
    if m.get("method") == "adding-doubling":
        print(f"target met    {'yes' if accuracy['target_met'] else 'NO'}: the solver's error bound, "
              f"max {m.get('error_bound_max_rel', 0):.3g} relative")
    else:
        print(f"target met    {'yes' if accuracy['target_met'] else 'NO'}: {accuracy['capped_cells']} of "
              f"{table.samples.size} cells stopped at --max-samples {accuracy['max_samples']}")
    if not accuracy["target_met"] and m.get("method") == "adding-doubling":
        print(f"bsdflab tabulate: warning: the solver's error bound exceeds the target "
              f"{table.rel_error_target:g} somewhere (docs/solvers.md: more nodes)", file=sys.stderr)
    elif not accuracy["target_met"]:
        print(f"bsdflab tabulate: warning: the table does not reach the target error "
              f"{table.rel_error_target:g} everywhere; raise --max-samples", file=sys.stderr)
    return 0
