"""The full model's instrument terms on gonio rows (bsdflab.fit.gonio_instrument): the cost
of one direct forward evaluation (one parameter set, all rows: a solve and an eval) with
every term off, an angle offset, a 3 deg cone, a 20 nm slit, and all three, in one run.

Workload: the 11 geometries of examples/fit/structure_full at 450, 550, 650 nm (33 rows),
the example's structure; each evaluation changes sigma_s, so every one is a full solve
(nothing is reused from the last). Prints seconds per evaluation (median of ``--repeats``)
and the ratio to the terms off.

    python3 bench/bench_fit_full_instrument.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
import tomllib

from bsdflab.fit.data import read_csv
from bsdflab.fit.full_stack_config import FullStackConfig
from bsdflab.fit.full_stack_posterior import FullStackPosterior

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLE = os.path.join(HERE, "..", "examples", "fit", "structure_full")
CASES = {
    "off": {},
    "offset 1 deg": {"angle_offset_deg": 1.0},
    "cone 3 deg": {"acceptance_deg": 3.0},
    "slit 20 nm": {"bandwidth_nm": 20.0},
    "all three": {"angle_offset_deg": 1.0, "acceptance_deg": 3.0, "bandwidth_nm": 20.0},
}


def seconds(values: dict, data, repeats: int) -> float:
    with open(os.path.join(EXAMPLE, "structure.toml"), "rb") as f:
        d = tomllib.load(f)
    d["model"]["emulator_nodes"] = 0
    d["instrument"].update(values)
    post = FullStackPosterior([data], FullStackConfig.parse(d))
    v = np.array([post.config.fixed.get(n, post.config.domains[n].default) for n in post.config.names])
    times = []
    for i in range(repeats):
        v[post.col["sigma_s"]] = 0.3 + 0.01 * i  # a new slab: a full solve
        t = time.perf_counter()
        y = post.solver.evaluate(v)
        times.append(time.perf_counter() - t)
        assert np.all(np.isfinite(y))
    return float(np.median(times))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    data = read_csv(os.path.join(EXAMPLE, "data.csv"))
    print(
        f"load average {os.getloadavg()[0]:.1f}, BSDFLAB_THREADS={os.environ.get('BSDFLAB_THREADS', 'all')}, "
        f"{len(data)} rows"
    )
    base = None
    for name, values in CASES.items():
        s = seconds(values, data, args.repeats)
        base = base or s
        print(f"{name:14s} {s:8.2f} s per evaluation  {s / base:6.1f}x")


if __name__ == "__main__":
    main()
