"""Convergence of the adding-doubling solver in its truncations (docs/solvers.md's table).

    python bench/solver_convergence.py

For each configuration: the largest relative error, over 12 direction pairs (grazing
ones included, outside cosines 1 ... 0.017) and 3 wavelengths, of the light that entered
the stack (``scattered_only``) against a reference solve (48 nodes per panel, 1.5 x the
automatic orders, start depth 2^-20, 8 x the automatic azimuth samples), for a sweep of
one truncation at a time from the defaults (16 nodes, automatic orders, 2^-16, automatic
azimuth samples); and the default's a-posteriori bound.
"""
from __future__ import annotations

import warnings

import numpy as np

import bsdflab as bl
from bsdflab.presets import preset
from bsdflab.solvers import solve
from bsdflab.testing import random_unit_vectors, spherical_directions

WL = [450.0, 550.0, 650.0]
SLAB = bl.Slab(2.0, sigma_a=0.1, sigma_s=0.5, phase={"type": "hg", "g": 0.6})
CONFIGS = {
    "smooth 1.5 / HG 0.6 tau 5, albedo 0.9 / Lambertian 0.5":
        lambda: bl.Layered([bl.Dielectric(1.5, 1.0)], [bl.Slab(1.0, sigma_a=0.5, sigma_s=4.5,
                                                                phase={"type": "hg", "g": 0.6})], bl.Diffuse(0.5)),
    "xenopeltis (GGX 0.08 + guanine film / melanin HG slab / base)": lambda: preset("xenopeltis"),
    "GGX 0.05 + film / HG 0.6 slab / Lambertian": lambda: bl.Layered(
        [bl.RoughDielectric(0.05, 1.5, 1.0, film=[{"material": 1.83, "thickness_nm": 400.0}])], [SLAB],
        bl.Diffuse(0.5)),
    "Beckmann 0.5 / HG 0.6 slab / Lambertian": lambda: bl.Layered(
        [bl.RoughDielectric(0.5, 1.5, 1.0, distribution="beckmann")], [SLAB], bl.Diffuse(0.5)),
}


def pairs():
    wi = random_unit_vectors(12, seed=31, hemisphere="upper")
    wo = random_unit_vectors(12, seed=32, hemisphere="upper")
    graze = spherical_directions(np.radians([85.0, 89.0, 30.0, 88.0]), [0.0, 1.0, 2.0, 4.0])
    wi[:4], wo[4:8] = graze, graze
    return wi, wo


def main() -> None:
    warnings.simplefilter("ignore")
    wi, wo = pairs()
    cols = ["nodes 16", "nodes 24", "nodes 32", "orders 1/2", "orders 3/4", "thin 2^-12", "azimuth x2", "azimuth x4",
            "defaults", "bound"]
    print("| configuration | " + " | ".join(cols) + " |")
    print("|---|" + "---|" * len(cols))
    for name, make in CONFIGS.items():
        model = make()
        default = solve(model, WL)
        auto, h = default.orders, default.azimuth_samples
        ref = solve(model, WL, nodes=48, orders=max(2, int(1.5 * auto)), thin_depth=2.0**-20,
                    azimuth_samples=8 * h).eval(wi, wo, scattered_only=True)

        def err(model=model, ref=ref, **kw):
            v = solve(model, WL, **kw).eval(wi, wo, scattered_only=True)
            return float(np.max(np.abs(v - ref) / np.abs(ref)))

        row = [err(nodes=16), err(nodes=24), err(nodes=32), err(orders=max(1, auto // 2)),
               err(orders=max(1, (3 * auto) // 4)), err(thin_depth=2.0**-12), err(azimuth_samples=2 * h),
               err(azimuth_samples=4 * h), err()]
        value, bound = solve(model, WL).eval_with_error(wi, wo, scattered_only=True)
        row.append(float(np.max(bound / np.abs(value))))
        print(f"| {name} (orders {auto}) | " + " | ".join(f"{x:.1e}" for x in row) + " |")


if __name__ == "__main__":
    main()
