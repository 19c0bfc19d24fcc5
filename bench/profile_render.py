"""A small render for profilers: ``perf record -g -- python bench/profile_render.py snake``.

Renders one scene (``basic-materials`` or ``snake``) at a small size after warming the
caches (tables are tabulated or read before the timed part), so a profile shows the path
tracer and not the build. See bench/README.md for the profile commands.
"""
from __future__ import annotations

import argparse
import os
import time

from bsdflab.render import render
from bsdflab.scenes import scene


def rough_tables(s):
    from dataclasses import replace

    materials = {}
    for name, m in s.materials.items():
        if m.bsdf.get("type") == "tabulated":
            m = replace(m, bsdf={**m.bsdf, "rel_error": 0.5, "min_samples": 8})
        materials[name] = m
    return replace(s, materials=materials)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("scene", choices=("basic-materials", "snake"))
    p.add_argument("--width", type=int, default=160)
    p.add_argument("--height", type=int, default=90)
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--spectral", action="store_true")
    p.add_argument("--rough-table", action="store_true",
                   help="tabulate the snake at 50 %% error with 8 walks per cell (seconds instead of minutes): "
                        "the render's cost does not depend on the table's accuracy")
    p.add_argument("--exact-top", action="store_true", help="tables: evaluate the top film spectrally (no lookup)")
    args = p.parse_args()
    if args.exact_top:
        from bsdflab.tables import table_bsdf

        table_bsdf.FILM_LOOKUP = False
    s = scene(args.scene, width=args.width, height=args.height)
    if args.rough_table:
        s = rough_tables(s)
    kwargs = {"spectral": True} if args.spectral else {}
    render(s.with_resolution(8, 8), spp=1, progress=False, **kwargs)  # builds / reads tables
    cpu = time.process_time()
    r = render(s, spp=args.spp, seed=1, progress=False, **kwargs)
    cpu = time.process_time() - cpu
    samples = r.mean.shape[0] * r.mean.shape[1] * r.spp
    # CPU time counts every thread's work: on a loaded machine samples per CPU-second is the
    # steadier measure (x cores = the rate an idle machine would reach).
    print(f"{args.scene}: {r.samples_per_second / 1e3:.0f} k samples/s wall ({r.seconds:.2f} s), "
          f"{samples / cpu / 1e3:.0f} k samples per CPU-second ({cpu:.2f} CPU-s), "
          f"{r.rays_traced / cpu / 1e6:.2f} M rays per CPU-second; load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
