"""Convergence of the adding-doubling oracle in its three truncations.

For each configuration, eval over direction pairs that include grazing ones (outside
cosines down to 0.02) is compared with a reference run far beyond the defaults
(REFERENCE); one setting is varied at a time, the others held at the reference. The
number reported is the largest relative difference over the pairs.

Run: ``python -m bsdflab.oracles.ad_convergence`` (prints a markdown table; a few
minutes on one core). docs/oracles.md keeps its output.
"""
from __future__ import annotations

import numpy as np

from bsdflab.layered.slab import Slab
from bsdflab.oracles.slab_adding_doubling import NODES, THIN_DEPTH, AddingDoublingOracle

REFERENCE = {"nodes": 48, "orders": 64, "thin_depth": 2.0 ** -30}

CONFIGURATIONS = {
    "isotropic, tau 1, albedo 0.9, Lambertian 0.5": (
        dict(slabs=[Slab.from_albedo(1.0, 0.9, 1.0)], base_albedo=0.5)),
    "HG 0.6, tau 5, albedo 0.99, Lambertian 0.5": (
        dict(slabs=[Slab.from_albedo(5.0, 0.99, 1.0, {"type": "hg", "g": 0.6})], base_albedo=0.5)),
    "HG -0.3, tau 0.5, albedo 0.5, black": (
        dict(slabs=[Slab.from_albedo(0.5, 0.5, 1.0, {"type": "hg", "g": -0.3})], base_albedo=0.0)),
    "HG 0.6, tau 1, albedo 0.95, glass to air (T)": (
        dict(slabs=[Slab.from_albedo(1.0, 0.95, 1.0, {"type": "hg", "g": 0.6})], base_ior=1.0)),
}

SWEEPS = {
    "nodes": [8, 16, 24, 32],
    "orders": [12, 24, 36],
    "thin_depth": [2.0 ** -16, 2.0 ** -22, 2.0 ** -28],
}


def directions() -> tuple[np.ndarray, np.ndarray]:
    """Pairs over outside cosines {1, 0.7, 0.3, 0.1, 0.02} x the same, azimuth 0.3 and 2.5;
    the second direction is mirrored below for the transmissive configuration."""
    c = np.array([1.0, 0.7, 0.3, 0.1, 0.02])
    ci, co, ph = (a.ravel() for a in np.meshgrid(c, c, [0.3, 2.5], indexing="ij"))
    si, so = np.sqrt(1 - ci ** 2), np.sqrt(1 - co ** 2)
    wi = np.stack([si, np.zeros_like(si), ci], axis=1)
    wo = np.stack([so * np.cos(ph), so * np.sin(ph), co], axis=1)
    return wi, wo


def convergence_study(wavelength: float = 550.0, report=None) -> list[dict]:
    """Rows {configuration, setting, value, max_relative_error}; `report(row)` is
    called as each is measured."""
    wi, wo = directions()
    rows = []
    for name, params in CONFIGURATIONS.items():
        w2 = wo * np.array([1, 1, -1]) if "base_ior" in params else wo
        ref = AddingDoublingOracle(1.5, 1.0, **params, **REFERENCE).eval(wi, w2, [wavelength])[:, 0]
        for setting, values in SWEEPS.items():
            for v in values:
                o = AddingDoublingOracle(1.5, 1.0, **params, **{**REFERENCE, setting: v})
                err = np.max(np.abs(o.eval(wi, w2, [wavelength])[:, 0] / ref - 1))
                rows.append({"configuration": name, "setting": setting, "value": v,
                             "max_relative_error": float(err)})
                if report:
                    report(rows[-1])
        default = AddingDoublingOracle(1.5, 1.0, **params)
        err = np.max(np.abs(default.eval(wi, w2, [wavelength])[:, 0] / ref - 1))
        rows.append({"configuration": name, "setting": "defaults",
                     "value": f"{NODES} nodes, auto orders, 2^{np.log2(THIN_DEPTH):.0f}",
                     "max_relative_error": float(err)})
        if report:
            report(rows[-1])
    return rows


def _value(setting, v) -> str:
    return f"2^{np.log2(v):.0f}" if setting == "thin_depth" else str(v)


def main() -> None:
    print("| configuration | setting | value | max relative error |")
    print("|---|---|---|---|")

    def row(r):
        v = r["value"] if r["setting"] == "defaults" else _value(r["setting"], r["value"])
        print(f"| {r['configuration']} | {r['setting']} | {v} | {r['max_relative_error']:.1e} |",
              flush=True)

    convergence_study(report=row)


if __name__ == "__main__":
    main()
