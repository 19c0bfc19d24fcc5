"""The renderer against Mitsuba 3, and table-driven vs direct-PFMC rendering of the snake.

(a) The basic-materials scene (diffuse, conductors, dielectrics, rough variants, an area
    light and a constant environment) at the same resolution, spp and max_depth in
    bsdflab and in Mitsuba 3's scalar_rgb and llvm_ad_rgb variants (each Mitsuba variant
    in its own subprocess: a variant is fixed per process). Times are render calls only;
    Mitsuba's llvm variant is timed on a second, warm call (its first call compiles
    kernels; that time is printed too). Prints samples/s and the ratios.
(b) Equal-time error on a small snake image: a reference rendered with direct PFMC at
    high spp; then the table material and direct PFMC each given the same render time.
    Error = mean squared error against the reference minus the reference's own variance.
    Prints the MSE ratio direct / table (how much more time direct PFMC would need).

    python bench/bench_render.py                 # README figures (~10 minutes on 2 cores)
    python bench/bench_render.py --quick         # a smoke run
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

MITSUBA_VARIANTS = ("scalar_rgb", "llvm_ad_rgb")


def mitsuba_worker(width: int, height: int, spp: int) -> None:
    """Subprocess body: time Mitsuba on basic-materials in the variant from the environment."""
    from bsdflab.reference.mitsuba_env import mitsuba
    from bsdflab.reference.mitsuba_scene import to_mitsuba_scene
    from bsdflab.scenes import scene

    mi = mitsuba()
    mi_scene = mi.load_dict(to_mitsuba_scene(scene("basic-materials", width=width, height=height), spp=spp))
    times = []
    for seed in (0, 1):
        start = time.perf_counter()
        image = mi.render(mi_scene, spp=spp, seed=seed)
        np.asarray(image)  # wait for the kernel to finish
        times.append(time.perf_counter() - start)
    print(json.dumps({"variant": mi.variant(), "first_s": times[0], "warm_s": times[1]}))


def bench_mitsuba(width: int, height: int, spp: int) -> dict:
    print(f"(a) basic-materials {width}x{height}, {spp} spp, max_depth 6")
    from bsdflab.render import render
    from bsdflab.scenes import scene

    s = scene("basic-materials", width=width, height=height)
    render(s.with_resolution(16, 16), spp=1, progress=False)  # warm the caches
    ours = render(s, spp=spp, seed=1, progress=False)
    samples = width * height * spp
    rows = {"bsdflab": ours.seconds}
    for variant in MITSUBA_VARIANTS:
        env = dict(os.environ, BSDFLAB_MITSUBA_VARIANT=variant)
        out = subprocess.run([sys.executable, __file__, "--mitsuba-worker", str(width), str(height), str(spp)],
                             env=env, capture_output=True, text=True, check=True)
        r = json.loads(out.stdout.strip().splitlines()[-1])
        rows[f"mitsuba {r['variant']}"] = r["warm_s"]
        print(f"  mitsuba {r['variant']:<12} first call {r['first_s']:.2f} s (includes JIT for llvm)")
    for name, seconds in rows.items():
        print(f"  {name:<22} {seconds:7.2f} s  {samples / seconds / 1e6:6.2f} M samples/s  "
              f"bsdflab speed-up {seconds / rows['bsdflab']:5.2f}x")
    return rows


def mse_against(result, reference) -> float:
    return float(np.mean((result.mean - reference.mean) ** 2) - np.mean(reference.variance))


def bench_equal_time(width: int, height: int, ref_spp: int, table_spp: int) -> dict:
    print(f"(b) snake {width}x{height}: table vs direct PFMC at equal time (reference: direct, {ref_spp} spp)")
    from bsdflab.render import render
    from bsdflab.scenes import scene

    direct = scene("snake", material="direct", width=width, height=height)
    table = scene("snake", material="table", width=width, height=height)
    reference = render(direct, spp=ref_spp, seed=100, progress=True)
    t = render(table, spp=table_spp, seed=1, progress=False)
    probe = render(direct, spp=max(1, table_spp // 16), seed=2, progress=False)
    direct_spp = max(1, round(t.seconds / (probe.seconds / probe.spp)))
    d = render(direct, spp=direct_spp, seed=3, progress=False)
    mse_t, mse_d = mse_against(t, reference), mse_against(d, reference)
    print(f"  reference: {reference.seconds:.1f} s")
    print(f"  table : {t.spp:5d} spp in {t.seconds:6.2f} s  MSE {mse_t:.3e}")
    print(f"  direct: {d.spp:5d} spp in {d.seconds:6.2f} s  MSE {mse_d:.3e}")
    print(f"  equal-time MSE ratio direct / table: {mse_d / mse_t:.1f}x")
    return {"table_mse": mse_t, "direct_mse": mse_d, "ratio": mse_d / mse_t}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small sizes (smoke run)")
    p.add_argument("--mitsuba-worker", nargs=3, type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.mitsuba_worker:
        mitsuba_worker(*args.mitsuba_worker)
        return
    from bsdflab import _core

    print(f"threads: {_core.worker_count()}")
    if args.quick:
        bench_mitsuba(64, 48, 16)
        bench_equal_time(32, 18, 64, 16)
    else:
        bench_mitsuba(320, 240, 64)
        bench_equal_time(96, 54, 512, 64)


if __name__ == "__main__":
    main()
