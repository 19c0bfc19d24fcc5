"""Measured materials: bl.Measured (RGL .bsdf) eval/sample throughput against Mitsuba 3's
native ``measured`` plugin (llvm_ad_rgb: one kernel over all queries, timed after compiling; scalar_rgb: one Python call
per query, so it measures Python's call overhead as much as the plugin) on the
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
    for variant, count in (("llvm_ad_rgb", n), ("scalar_rgb", min(n, 5000))):
        try:
            ev, sa = _mitsuba_rates(variant, out, wi[:count], wo[:count], u1[:count], u2[:count])
        except Exception as e:  # a variant this build lacks
            print(f"{variant}: unavailable ({e})")
            continue
        rates[f"Mitsuba {variant} eval"], rates[f"Mitsuba {variant} sample"] = ev, sa
    for name, r in rates.items():
        print(f"{name:40s} {r / 1e6:8.3f} M queries/s")
    for what in ("eval", "sample"):
        ours = rates[f"bl.Measured {what}"]
        print(f"ratio bl.Measured {what} / TableBSDF {what}: {ours / rates[f'TableBSDF {what}']:.2f}")
        for variant in ("llvm_ad_rgb", "scalar_rgb"):
            key = f"Mitsuba {variant} {what}"
            if key in rates:
                print(f"ratio bl.Measured {what} / {key}: {ours / rates[key]:.2f}")


def _mitsuba_rates(variant, path, wi, wo, u1, u2):
    """Queries per second of Mitsuba's measured plugin: the plugin loaded once; llvm: one
    kernel over all queries (timed after a warm-up that compiles it); scalar: a loop."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    bsdf = mi.load_dict({"type": "measured", "filename": path})
    ctx = mi.BSDFContext()
    n = len(wi)
    frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    if variant.startswith("llvm"):
        f32 = lambda a: np.ascontiguousarray(a, dtype=np.float32)
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(*[mi.Float(f32(wi[:, k])) for k in range(3)])
        si.sh_frame = frame
        w = mi.Vector3f(*[mi.Float(f32(wo[:, k])) for k in range(3)])
        s1, s2 = mi.Float(f32(u1)), mi.Point2f(mi.Float(f32(u2[:, 0])), mi.Float(f32(u2[:, 1])))

        def ev():
            dr.eval(bsdf.eval(ctx, si, w))
            dr.sync_thread()

        def sa():
            bs, weight = bsdf.sample(ctx, si, s1, s2)
            dr.eval(bs.wo, weight)
            dr.sync_thread()
        ev(), sa()  # compile
        return _rate(ev, n)[0], _rate(sa, n)[0]
    si = mi.SurfaceInteraction3f()
    si.sh_frame = frame
    pairs = [(mi.Vector3f(*a.tolist()), mi.Vector3f(*b.tolist()), float(c), mi.Point2f(*d.tolist()))
             for a, b, c, d in zip(wi, wo, u1, u2)]

    def ev():
        for a, b, _, _ in pairs:
            si.wi = a
            bsdf.eval(ctx, si, b)

    def sa():
        for a, _, c, d in pairs:
            si.wi = a
            bsdf.sample(ctx, si, c, d)
    return _rate(ev, n, repeat=1)[0], _rate(sa, n, repeat=1)[0]

if __name__ == "__main__":
    main()
