"""Export time per format for the snake (fit included), against the fit alone as the peer.

    .venv/bin/python bench/bench_export.py [--repeat N]

Prints, per format, the wall time of ``bsdflab.export.export`` (fit + files + report) and
its ratio to the fit alone for that target, measured in the same run. No assertions.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time


def main() -> None:
    from bsdflab.export import export
    from bsdflab.export.fit import fit
    from bsdflab.export.material import export_material
    from bsdflab.export.targets import TARGETS
    from bsdflab.presets import xenopeltis

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    snake = xenopeltis().to_dict()
    names = {"openpbr": "snake.mtlx", "gltf": "snake.glb", "usd": "snake.usda", "blender": "snake.blend"}
    print(f"load average {os.getloadavg()[0]:.1f}; snake (xenopeltis), best of {args.repeat}")
    print(f"{'format':9s} {'export (s)':>10s} {'fit alone (s)':>13s} {'export / fit':>12s}  median dE00  >2")
    with tempfile.TemporaryDirectory() as folder:
        for fmt, name in names.items():
            t_fit = t_exp = float("inf")
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                fit(export_material(snake), TARGETS[fmt])
                t_fit = min(t_fit, time.perf_counter() - t0)
                t0 = time.perf_counter()
                report = export(snake, fmt, os.path.join(folder, name), name="xenopeltis")
                t_exp = min(t_exp, time.perf_counter() - t0)
            e = report["delta_e00"]
            print(f"{fmt:9s} {t_exp:10.2f} {t_fit:13.2f} {t_exp / t_fit:12.2f}  {e['median']:10.2f}  "
                  f"{100 * e['share_above_2']:.0f} %")


if __name__ == "__main__":
    main()
