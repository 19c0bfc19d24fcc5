"""The RGL writer's resampling error (docs/measured.md, "The resampling error"): each
source exported three ways on the same grid (the error points: every cell centre, the
same for all three, plus random pairs half drawn from each file's own sampler): the NDF without
the shadowing correction (one step, D ~ f(m, m) cos^2) and the plain VNDF warp (the
writer before); the paper's power-iteration NDF (the default); and that NDF with the
warp's cosine floor 0.5 (an option, ``vndf_floor``).

    python bench/measured_error_table.py [--resolution 32] [--theta-i 16] [--points 10000]
"""
from __future__ import annotations

import argparse
import time


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolution", type=int, default=32)
    ap.add_argument("--theta-i", type=int, default=16)
    ap.add_argument("--points", type=int, default=10000)
    ap.add_argument("--no-snake", action="store_true", help="skip the tabulated snake (slowest)")
    args = ap.parse_args()

    from bsdflab.bsdfs import Diffuse, RoughConductor
    from bsdflab.measured.rgl import NDF_ITERATIONS, rgl_from_bsdf

    sources = [("Diffuse 0.5", lambda: Diffuse(0.5)),
               ("RoughConductor Au, alpha 0.2", lambda: RoughConductor(alpha=0.2, material="Au")),
               ("RoughConductor Cu, alpha 0.05", lambda: RoughConductor(alpha=0.05, material="Cu"))]
    if not args.no_snake:
        def snake():
            from bsdflab.presets import xenopeltis
            from bsdflab.render.build import resolve_bsdf

            return resolve_bsdf({"type": "tabulated", "model": xenopeltis().to_dict(), "min_samples": 256,
                                 "grid": {"n_theta_i": 6, "n_theta_o": 12, "n_phi": 7, "thickness_nm": []},
                                 "rel_error": 0.05})
        sources.insert(0, ("snake table 6 x 12 x 7", snake))
    print(f"n_theta_i {args.theta_i}, resolution {args.resolution}, {args.points} random points + cell centres")
    print("| source | NDF | max abs error | peak | max / peak | max, <= 60 deg | rms | s |")
    print("|---|---|---|---|---|---|---|---|")
    for name, make in sources:
        bsdf = make()
        wl = None
        if hasattr(bsdf, "table"):  # a TableBSDF is exported at its own channels, as export_table does
            from bsdflab.tables.channels import channel_wavelengths

            wl = channel_wavelengths(bsdf.table.channels)
        for label, iters, floor in (("before: cos^2 NDF, VNDF", 1, 0.0),
                                    ("power-iteration NDF, VNDF", NDF_ITERATIONS, 0.0),
                                    ("power-iteration NDF, warp floor 0.5", NDF_ITERATIONS, 0.5)):
            t = time.perf_counter()
            _, r = rgl_from_bsdf(bsdf, wl, n_theta_i=args.theta_i, resolution=args.resolution,
                                 ndf_iterations=iters, vndf_floor=floor, error_points=args.points)
            print(f"| {name} | {label} | {r.max_abs_error:.3g} | {r.peak:.3g} | {r.relative_error:.1%} | "
                  f"{r.max_abs_error_60:.3g} ({r.max_abs_error_60 / r.peak:.2%}) | {r.rms_error:.3g} | "
                  f"{time.perf_counter() - t:.1f} |", flush=True)


if __name__ == "__main__":
    main()
