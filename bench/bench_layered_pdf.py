"""The layered pdf as an MIS density: a direct-PFMC render of the snake, old pdf vs new.

The path tracer weights light samples and BSDF samples by the power heuristic over
(light pdf, Layered.pdf). Any fixed function of (wi, wo) keeps the render unbiased; the
closer it is to the density with which Layered.sample returns directions, the lower the
variance. Compared, in one run, on the same scene and seeds:
  * ``pdf_samples=0``: estimator version 4's deterministic approximation (integrates to 1,
    while the sampler returns a direction for only 0.65-0.68 of its draws);
  * ``pdf_samples=n``: the walk's own exit density, estimated with n walks
    (docs/estimators.md).
Each variant renders a probe to measure its time per spp, then the spp that fills the
same time budget; the figure of merit is the mean per-pixel variance of the mean over the
snake's pixels (body and head meshes), and efficiency = 1 / (variance x seconds). Ratios
are printed against the old pdf.

Run: python bench/bench_layered_pdf.py [--width 96 --height 54 --seconds 60 --pdf-samples 1 4 16]
"""
from __future__ import annotations

import argparse
import dataclasses
import os

import numpy as np

from bsdflab.render import render
from bsdflab.scenes import scene


def with_pdf_samples(sc, n: int):
    """The scene with every layered material's pdf_samples set to n."""
    materials = {}
    for name, m in sc.materials.items():
        if m.bsdf.get("type") == "layered":
            m = dataclasses.replace(m, bsdf={**m.bsdf, "pdf_samples": n})
        materials[name] = m
    return dataclasses.replace(sc, materials=materials)


def snake_mask(sc, result) -> np.ndarray:
    ids = [i for i, sh in enumerate(sc.shapes) if sh.name in ("body", "head")]
    return np.isin(result.aovs["mesh_id"], ids)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=int, default=96)
    ap.add_argument("--height", type=int, default=54)
    ap.add_argument("--seconds", type=float, default=60.0, help="render time per variant")
    ap.add_argument("--pdf-samples", type=int, nargs="+", default=[1, 4, 16])
    args = ap.parse_args()
    base = scene("snake", material="direct", width=args.width, height=args.height)
    print(f"snake {args.width}x{args.height}, direct PFMC, {args.seconds:.0f} s per variant; "
          f"load average {os.getloadavg()[0]:.1f} at start")
    rows = []
    for n in [0, *args.pdf_samples]:
        sc = with_pdf_samples(base, n)
        probe = render(sc, spp=4, seed=2, progress=False)
        spp = max(4, round(args.seconds / (probe.seconds / probe.spp)))
        r = render(sc, spp=spp, seed=3, progress=False, aovs=True)
        mask = snake_mask(sc, r)
        var = float(np.mean(r.variance[mask]))
        rows.append((n, spp, r.seconds, var, 1.0 / (var * r.seconds)))
        label = "old (v4 approximation)" if n == 0 else f"walk density, {n} walks"
        print(f"  {label:24s}: {spp:5d} spp in {r.seconds:6.1f} s, mean pixel variance {var:.4e}")
    old = rows[0]
    for n, _spp, sec, var, eff in rows[1:]:
        print(f"  pdf_samples={n:2d}: variance ratio old/new at equal time "
              f"{old[3] * old[2] / (var * sec):.3f}x (efficiency ratio new/old {eff / old[4]:.3f})")


if __name__ == "__main__":
    main()
