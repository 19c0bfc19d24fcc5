"""A small render for profilers: ``perf record -g -- python bench/profile_render.py snake``.

Renders one scene (``basic-materials`` or ``snake``) at a small size after warming the
caches (tables are tabulated or read before the timed part), so a profile shows the path
tracer and not the build. See bench/README.md for the profile commands.
"""
from __future__ import annotations

import argparse

from bsdflab.render import render
from bsdflab.scenes import scene


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("scene", choices=("basic-materials", "snake"))
    p.add_argument("--width", type=int, default=160)
    p.add_argument("--height", type=int, default=90)
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--spectral", action="store_true")
    args = p.parse_args()
    s = scene(args.scene, width=args.width, height=args.height)
    kwargs = {"spectral": True} if args.spectral else {}
    r = render(s, spp=args.spp, seed=1, progress=False, **kwargs)
    print(f"{args.scene}: {r.samples_per_second / 1e3:.0f} k samples/s ({r.seconds:.2f} s)")


if __name__ == "__main__":
    main()
