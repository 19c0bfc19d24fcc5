"""The renderer against Mitsuba 3 and against Embree alone, and table-driven vs direct-PFMC
rendering of the snake; ends with the issue's metrics as ratios from this one run.

(a) The basic-materials scene (diffuse, conductors, dielectrics, rough variants, an area
    light and a constant environment) at the same resolution, spp and max_depth in
    bsdflab and in Mitsuba 3's scalar_rgb and llvm_ad_rgb variants (each Mitsuba variant
    in its own subprocess: a variant is fixed per process). Times are render calls only;
    Mitsuba's llvm variant is timed on a second, warm call (its first call compiles
    kernels; that time is printed too). Prints samples/s and the ratios.
(b) The snake (table material) at the same resolution and spp: samples/s against (a).
(c) The limit: the rays one sample per pixel of each scene traces (camera, bounce and
    shadow rays, recorded by the renderer) traced again by Embree alone
    (rtcIntersect1 / rtcOccluded1 on all cores, nothing else, and again in 16-wide packets
    as a wavefront renderer traces them); bsdflab's rays/s during the render as a fraction
    of Embree's rays/s on those rays, and Mitsuba llvm's rays/s (at bsdflab's rays per
    sample) against the packet limit.
(d) Equal-time error on a small snake image, snake pixels only (the ground masked out by
    the first-hit mesh image): a reference rendered with direct PFMC at high spp; then the
    table material and direct PFMC each given the same render time. Error = mean squared
    error against the reference minus the reference's own variance. Prints the MSE ratio
    direct / table (how much more time direct PFMC would need).

    python bench/bench_render.py                 # README figures (~10 minutes on 2 cores)
    python bench/bench_render.py --quick         # a smoke run

Profiling: see bench/README.md (perf on bench/profile_render.py).
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
RAYS_RECORDED = 400_000


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


def samples_per_second(result) -> float:
    return result.samples_per_second


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
    return {"result": ours, "rows": rows}


def bench_snake(width: int, height: int, spp: int) -> dict:
    print(f"(b) snake (table) {width}x{height}, {spp} spp, max_depth 8")
    from bsdflab.render import render
    from bsdflab.scenes import scene

    s = scene("snake", width=width, height=height)
    render(s.with_resolution(16, 9), spp=1, progress=True)  # tabulates on first use
    r = render(s, spp=spp, seed=1, progress=False)
    print(f"  {r.seconds:.2f} s  {r.samples_per_second / 1e6:.3f} M samples/s")
    return {"result": r}


def bench_embree_limit(name: str, width: int, height: int, result) -> float:
    """bsdflab rays/s during ``result``'s render over Embree-alone rays/s on recorded rays."""
    from bsdflab import _core
    from bsdflab.render.build import build_render_scene
    from bsdflab.scenes import scene

    s = scene(name, width=width, height=height)
    core_scene = build_render_scene(s)
    job = _core.RenderJob(core_scene, 1, 1, s.max_depth, s.rr_depth, 1, 16, 0)
    rays = job.record_rays(RAYS_RECORDED)
    core_scene.embree_seconds(rays[: len(rays) // 10])  # warm
    seconds = min(core_scene.embree_seconds(rays) for _ in range(3))
    packet_seconds = min(core_scene.embree_seconds(rays, packet=16) for _ in range(3))
    embree_rate, packet_rate = len(rays) / seconds, len(rays) / packet_seconds
    ours = result.rays_traced / result.seconds
    shadow = float(np.mean(rays[:, 7]))
    print(f"(c) {name}: Embree alone {embree_rate / 1e6:.2f} M rays/s on {len(rays)} recorded rays "
          f"({shadow:.0%} shadow), {packet_rate / 1e6:.2f} M rays/s in 16-wide packets; "
          f"bsdflab {ours / 1e6:.2f} M rays/s while rendering = {ours / embree_rate:.2f} of the single-ray "
          f"limit, {ours / packet_rate:.2f} of the packet limit")
    return {"single": ours / embree_rate, "packet_rate": packet_rate, "rays_per_sample":
            result.rays_traced / (result.mean.shape[0] * result.mean.shape[1] * result.spp)}


def masked_mse(result, reference, mask) -> float:
    err = (result.mean - reference.mean)[mask]
    return float(np.mean(err ** 2) - np.mean(reference.variance[mask]))


def bench_equal_time(width: int, height: int, ref_spp: int, table_spp: int) -> dict:
    print(f"(d) snake {width}x{height}: table vs direct PFMC at equal time, snake pixels only "
          f"(reference: direct, {ref_spp} spp)")
    from bsdflab.render import render
    from bsdflab.scenes import scene

    direct = scene("snake", material="direct", width=width, height=height)
    table = scene("snake", material="table", width=width, height=height)
    reference = render(direct, spp=ref_spp, seed=100, progress=True, aovs=True)
    snake_meshes = [i for i, sh in enumerate(direct.shapes) if sh.name in ("body", "head")]
    mask = np.isin(reference.aovs["mesh_id"], snake_meshes)
    t = render(table, spp=table_spp, seed=1, progress=False)
    probe = render(direct, spp=max(1, table_spp // 16), seed=2, progress=False)
    direct_spp = max(1, round(t.seconds / (probe.seconds / probe.spp)))
    d = render(direct, spp=direct_spp, seed=3, progress=False)
    mse_t, mse_d = masked_mse(t, reference, mask), masked_mse(d, reference, mask)
    print(f"  reference: {reference.seconds:.1f} s; snake pixels: {mask.sum()} of {mask.size}")
    print(f"  table : {t.spp:5d} spp in {t.seconds:6.2f} s  MSE {mse_t:.3e}")
    print(f"  direct: {d.spp:5d} spp in {d.seconds:6.2f} s  MSE {mse_d:.3e}")
    print(f"  equal-time MSE ratio direct / table: {mse_d / mse_t:.1f}x")
    return {"table_mse": mse_t, "direct_mse": mse_d, "ratio": mse_d / mse_t}


def bench_spectral(width: int, height: int, spp: int, rgb_result):
    import inspect

    from bsdflab.render import render
    from bsdflab.scenes import scene

    if "spectral" not in inspect.signature(render).parameters:
        return None
    r = render(scene("snake", width=width, height=height), spp=spp, seed=1, progress=False, spectral=True)
    print(f"(e) snake spectral: {r.samples_per_second / 1e6:.3f} M samples/s")
    return r.samples_per_second / rgb_result.samples_per_second


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small sizes (smoke run)")
    p.add_argument("--mitsuba-worker", nargs=3, type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.mitsuba_worker:
        mitsuba_worker(*args.mitsuba_worker)
        return
    from bsdflab import _core

    print(f"threads: {_core.worker_count()}; load average {os.getloadavg()[0]:.1f} at start")
    w, h, spp = (64, 48, 16) if args.quick else (320, 240, 64)
    a = bench_mitsuba(w, h, spp)
    b = bench_snake(w, h, spp)
    limit_basic = bench_embree_limit("basic-materials", w, h, a["result"])
    limit_snake = bench_embree_limit("snake", w, h, b["result"])
    d = bench_equal_time(32, 18, 64, 16) if args.quick else bench_equal_time(96, 54, 512, 64)
    spectral = bench_spectral(w, h, max(1, spp // 4), b["result"])
    ours = a["rows"]["bsdflab"]
    main_job = 1280 * 720 * 256 / b["result"].samples_per_second
    print(f"\nmetrics (one run; load average {os.getloadavg()[0]:.1f} at the end)")
    print("| metric | this run |")
    print("|---|---|")
    print(f"| basic-materials samples/s vs Mitsuba llvm_ad_rgb | {a['rows']['mitsuba llvm_ad_rgb'] / ours:.2f}x |")
    print(f"| basic-materials samples/s vs Mitsuba scalar_rgb | {a['rows']['mitsuba scalar_rgb'] / ours:.2f}x |")
    print(f"| snake samples/s vs basic-materials samples/s | "
          f"{b['result'].samples_per_second / a['result'].samples_per_second:.2f} |")
    print(f"| snake, table vs direct PFMC, equal-time MSE, snake pixels | {d['ratio']:.1f}x |")
    print(f"| main job 1280x720x256 at this snake rate (extrapolated) | {main_job:.0f} s |")
    print(f"| bsdflab rays/s vs Embree alone, basic-materials / snake | "
          f"{limit_basic['single']:.2f} / {limit_snake['single']:.2f} |")
    # What the llvm target asks for in rays/s, if Mitsuba traces as many rays per sample.
    llvm_rays = w * h * spp / a["rows"]["mitsuba llvm_ad_rgb"] * limit_basic["rays_per_sample"]
    print(f"| Mitsuba llvm_ad_rgb at bsdflab's rays per sample vs Embree's 16-wide packet limit, basic-materials | "
          f"{llvm_rays / limit_basic['packet_rate']:.2f} (2x llvm would need {2 * llvm_rays / 1e6:.1f} M rays/s; "
          f"the packet limit is {limit_basic['packet_rate'] / 1e6:.1f}) |")
    print(f"| spectral vs RGB samples/s, snake | {'not built' if spectral is None else f'{spectral:.2f}'} |")


if __name__ == "__main__":
    main()
