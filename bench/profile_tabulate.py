"""One small snake-table tabulation for profilers (bench/README.md, "Profiling the tabulator").

The snake's model (xenopeltis, 81 wavelengths per walk, RGB table) on a reduced grid with
the snake's three film-thickness nodes; prints walks per CPU-second (steadier than wall
time on a loaded machine) and the achieved error.

    python bench/profile_tabulate.py [--grid 3 6 4] [--rel-error 0.02]
"""
from __future__ import annotations

import argparse
import time


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--grid", type=int, nargs=3, default=(3, 6, 4), metavar=("N_THETA_I", "N_THETA_O", "N_PHI"))
    ap.add_argument("--rel-error", type=float, default=0.02)
    args = ap.parse_args()

    import bsdflab as bl
    from bsdflab.scenes.snake import table_grid
    from bsdflab.tables import TableGrid, tabulate

    nodes = table_grid()["thickness_nm"]
    grid = TableGrid(*args.grid, nodes)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    table = tabulate(bl.presets.xenopeltis(), grid, rel_error=args.rel_error, progress=False)
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    walks = int(table.samples.sum()) + int(table.meta["pilot_walks"])
    m = table.meta
    print(f"grid {args.grid} x {len(nodes)} thickness nodes: {walks} walks in {wall:.1f} s wall, {cpu:.1f} s CPU "
          f"-> {walks / cpu / 1e3:.1f} k walks per CPU-second ({cpu / walks * 1e6:.1f} CPU-us per walk); "
          f"rel_error rms {m['rel_error_rms']:.4f} p95 {m['rel_error_p95']:.4f}")


if __name__ == "__main__":
    main()
