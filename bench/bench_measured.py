"""Measured materials: bl.Measured (RGL .bsdf) eval/sample throughput against Mitsuba 3's
native ``measured`` plugin (llvm_ad_rgb vectorised, scalar_rgb one query per call) on the
same file and against bsdflab's own table lookup (TableBSDF); the writer's time for a
table; file sizes (RGL vs the bsdflab EXR). Prints ratios (same process, same queries).

    python bench/bench_measured.py [--table T.exr] [--n 200000]

Without --table a rough-copper table (8 x 16 x 9) is tabulated first.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np


def _rate(fn, n, repeat=3):
    best = min(_timed(fn) for _ in range(repeat))
    return n / best, best


def _timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--table", help="a bsdflab table (.exr); default: tabulate rough copper")
    ap.add_argument("--n", type=int, default=200_000)
    args = ap.parse_args()
    from bsdflab.bsdfs import RoughConductor
    from bsdflab.measured import Measured, export_table
    from bsdflab.measured.rgl import random_pairs
    from bsdflab.reference.mitsuba_calls import query
    from bsdflab.tables import TableBSDF, TableGrid, tabulate, write_table

    tmp = tempfile.mkdtemp()
    table = args.table
    if table is None:
        table = os.path.join(tmp, "copper.exr")
        write_table(table, tabulate(RoughConductor(alpha=0.3, material="Cu"),
                                    TableGrid(n_theta_i=8, n_theta_o=16, n_phi=9), rel_error=0.05, progress=False))
    out = os.path.join(tmp, "m.bsdf")
    t = time.perf_counter()
    report = export_table(table, out)
    write_s = time.perf_counter() - t
    print(f"writer: {write_s:.2f} s for {table}; {report.summary()}")
    exr, rgl = os.path.getsize(table), os.path.getsize(out)
    print(f"file sizes: EXR table {exr / 1024:.1f} KiB, RGL {rgl / 1024:.1f} KiB (ratio RGL/EXR {rgl / exr:.2f})")

    m, tb = Measured(out), TableBSDF(table)
    rng = np.random.default_rng(0)
    n = args.n
    wi, wo = random_pairs(m.reference, n, rng)
    wi, wo = wi.astype(np.float32).astype(float), wo.astype(np.float32).astype(float)
    u1, u2 = rng.random(n), rng.random((n, 2))
    rates = {}
    rates["bl.Measured eval"], _ = _rate(lambda: m.eval(wi, wo), n)
    rates["bl.Measured sample"], _ = _rate(lambda: m.sample(wi, u1, u2), n)
    rates["TableBSDF eval"], _ = _rate(lambda: tb.eval(wi, wo), n)
    rates["TableBSDF sample"], _ = _rate(lambda: tb.sample(wi, u1, u2), n)
    plugin = {"type": "measured", "filename": out}
    import mitsuba as mi

    for variant, count in (("llvm_ad_rgb", n), ("scalar_rgb", min(n, 2000))):
        try:
            mi.set_variant(variant)
        except Exception as e:  # a variant this build lacks
            print(f"{variant}: unavailable ({e})")
            continue
        k = slice(0, count)
        rates[f"Mitsuba {variant} eval+pdf+sample"], _ = _rate(
            lambda: query(plugin, wi[k], wo[k], u1[k], u2[k]), count, repeat=2)
    for name, r in rates.items():
        print(f"{name:40s} {r / 1e6:8.3f} M queries/s")
    ours = rates["bl.Measured eval"]
    print(f"ratio bl.Measured eval / TableBSDF eval: {ours / rates['TableBSDF eval']:.2f}")
    print(f"ratio bl.Measured sample / TableBSDF sample: {rates['bl.Measured sample'] / rates['TableBSDF sample']:.2f}")
    # query() runs eval, pdf and sample: compare with our three calls together.
    ours_all = 1.0 / (1 / ours + 1 / rates["bl.Measured sample"] + 1 / _rate(lambda: m.pdf(wi, wo), n)[0])
    for variant in ("llvm_ad_rgb", "scalar_rgb"):
        key = f"Mitsuba {variant} eval+pdf+sample"
        if key in rates:
            print(f"ratio bl.Measured (eval+pdf+sample) / {key}: {ours_all / rates[key]:.2f}")


if __name__ == "__main__":
    main()
