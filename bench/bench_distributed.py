"""Distributed tabulation: the same table on the in-process pool, on 1 and on 2 workers of a
LocalCluster, in one run; per-unit overhead, result transfer and the serial part; and the
cost model (bsdflab/distributed/cost_model.py) fed with those measurements for the spectral
fine-grid table on 16, 64 and 256 workers.

    python bench/bench_distributed.py            # ~3-5 minutes on 2 idle cores
    python bench/bench_distributed.py --quick    # a smaller table (~1 minute)

Parallel efficiency compares 2 single-threaded workers with 1 (BSDFLAB_THREADS=1 in each
worker); the in-process pool uses both cores through the C++ threads. On a shared machine
the absolute seconds move; the ratios from one run are what to read.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

# The spectral fine-grid table the model is asked about: 81 wavelengths (380-780 nm, 5 nm),
# 24 x 48 x 25 directions x 8 film-thickness nodes, 1 % target.
FINE_GRID = (24, 48, 25, 8)
FINE_REL_ERROR = 0.01


def table_setup(quick: bool):
    import bsdflab as bl
    from bsdflab.tables import TableGrid

    grid = TableGrid(4, 8, 5, (360.0, 440.0)) if quick else TableGrid(6, 12, 7, (340.0, 400.0, 460.0))
    return bl.presets.xenopeltis(), grid, dict(rel_error=0.03, wavelengths=None, min_samples=256,
                                             max_samples=8192, seed=0)


def timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def cluster_run(n_workers: int, threads: int, fn):
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None,
                      env={"BSDFLAB_THREADS": str(threads)}, silence_logs=40) as lc, Client(lc) as client:
        client.wait_for_workers(n_workers)
        client.run(lambda: __import__("bsdflab.tables.tabulate"))  # imports are not the job
        return fn(client)


def unit_overhead(client, n: int = 400) -> float:
    """Seconds per unit of the Dask runner for units that do nothing."""
    from bsdflab.distributed.probe import noop_unit
    from bsdflab.distributed.runner import DaskRunner

    t = time.perf_counter()
    DaskRunner(client).run(noop_unit, [], list(range(n)), lambda u, r: None, key=f"noop-{time.time_ns()}",
                           progress=False)
    return (time.perf_counter() - t) / n * len(client.scheduler_info()["workers"])


def transfer_rate(client, nbytes: int = 32 << 20) -> float:
    """Bytes/s of unit results coming back to the driver (loopback here)."""
    from bsdflab.distributed.probe import payload_unit
    from bsdflab.distributed.runner import DaskRunner

    t = time.perf_counter()
    DaskRunner(client).run(payload_unit, [nbytes // 8], list(range(8)), lambda u, r: None,
                           key=f"payload-{time.time_ns()}", progress=False)
    return 8 * (nbytes // 8) / (time.perf_counter() - t)


def spectral_cell_cost(quick: bool) -> tuple[float, float]:
    """(seconds of one core per cell, result bytes per cell) for an 81-wavelength table at
    the fine grid's 1 % target, from a few cells tabulated on one thread."""
    import bsdflab as bl
    from bsdflab import _core
    from bsdflab.spectra.grid import DEFAULT_WAVELENGTHS as WAVELENGTHS
    from bsdflab.tables import TableGrid, tabulate

    grid = TableGrid(2, 4, 3, (400.0,)) if quick else TableGrid(3, 6, 4, (400.0,))
    table, seconds = timed(lambda: tabulate(bl.presets.xenopeltis(), grid, rel_error=FINE_REL_ERROR,
                                            wavelengths=WAVELENGTHS, progress=False))
    cells = table.samples.size
    cpu = seconds * _core.worker_count()  # the job ran on every core
    channels = table.values.shape[-1]
    # Per cell the finish unit returns value and error per channel (float64), the sample
    # count (int32), luminance and its error (float64).
    return cpu / cells, channels * 2 * 8 + 4 + 2 * 8


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    from bsdflab import _core
    from bsdflab.distributed import cost_model as cm
    from bsdflab.distributed.runner import DaskRunner
    from bsdflab.tables import tabulate
    from bsdflab.tables.units import tabulate_units

    model, grid, kw = table_setup(args.quick)
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}; grid {grid.to_dict()}", flush=True)
    local, t_pool = timed(lambda: tabulate(model, grid, progress=False, **kw))
    cells = local.samples.size
    unit_cells = max(grid.n_theta_o * grid.n_phi, cells // 16)
    print(f"in-process pool ({_core.worker_count()} threads): {t_pool:.2f} s for {cells} cells", flush=True)

    def on_cluster(client):
        table, t = timed(lambda: tabulate_units(DaskRunner(client), model, grid, progress=False,
                                                unit_cells=unit_cells, **kw))
        same = all(np.array_equal(getattr(local, f), getattr(table, f)) for f in ("values", "stderr", "samples"))
        return t, same, table.meta["units"], table.meta["seconds"]

    t1, same1, units, compute1 = cluster_run(1, 1, on_cluster)
    t2, same2, _, compute2 = cluster_run(2, 1, on_cluster)
    overhead, rate = cluster_run(2, 1, lambda c: (unit_overhead(c), transfer_rate(c)))
    serial = max(0.0, t1 - compute1 - units * overhead)  # driver-side work outside the units
    efficiency = t1 / (2 * t2)
    t_cell, bytes_cell = spectral_cell_cost(args.quick)

    print(json.dumps({"cells": cells, "units_per_run": units, "unit_cells": unit_cells,
                      "in_process_s": round(t_pool, 2), "one_worker_s": round(t1, 2),
                      "two_workers_s": round(t2, 2), "identical_tables": bool(same1 and same2),
                      "speedup_2_vs_1_worker": round(t1 / t2, 3), "parallel_efficiency": round(efficiency, 3),
                      "two_workers_vs_in_process": round(t_pool / t2, 3),
                      "unit_overhead_ms": round(overhead * 1e3, 2), "result_MBps": round(rate / 1e6, 1),
                      "serial_s": round(serial, 2)}, indent=1))

    ti, to, ph, nt = FINE_GRID
    inputs = cm.CostInputs(items=ti * to * ph * nt, t_item_s=t_cell, t_unit_s=2 * overhead,  # two stages
                           bytes_per_item=bytes_cell, bandwidth_Bps=min(rate, 117e6),  # <= 1 GbE
                           t_serial_s=serial)
    print("cost model inputs (spectral fine grid, 81 wavelengths, 1 %):")
    print(json.dumps(inputs.as_dict(), indent=1))
    print(f"{'workers':>8} {'unit cells':>11} {'units':>7} {'hours':>8} {'speedup':>8} {'efficiency':>10}")
    for row in cm.scaling_table(inputs, (1, 16, 64, 256)):
        print(f"{row['workers']:>8} {row['unit_items']:>11} {row['units']:>7} {row['seconds'] / 3600:>8.2f} "
              f"{row['speedup']:>8.1f} {row['efficiency']:>10.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
