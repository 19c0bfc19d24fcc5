"""The main job's time split: table, build, render.

Runs `bsdflab render snake --width W --height H --spp N` (``./dev.sh demo``'s command by
default) as a fresh process with an empty table cache, then reads back

- table:  the first-use table's own ``meta["seconds"]`` (from the cache file it wrote),
          and its method (adding-doubling by default for the snake, docs/table_format.md);
- render: the command's ``render_seconds`` (its JSON summary);
- build:  the rest of the wall time: start-up and imports, the scene, meshes and Embree
          build, writing the EXR and PNG.

``--method pfmc`` runs the same job with the snake's table made by PFMC (the previous
default), as the peer of the same run.

    python bench/bench_main_job.py                        # the demo: 1280 x 720 x 256
    python bench/bench_main_job.py --spp 4 --method both  # a quick split, both methods
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]


def run(width: int, height: int, spp: int, method: str) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        cache, out = Path(tmp) / "cache", Path(tmp) / "snake.exr"
        args = [*BSDFLAB, "render", "snake", "--width", str(width), "--height", str(height), "--spp", str(spp),
                "--out", str(out), "--quiet"]
        if method == "pfmc":  # the snake's table by PFMC: the scene file's material with the method set
            scene = Path(tmp) / "snake.json"
            subprocess.run([*BSDFLAB, "render", "snake", "--save-scene", str(scene), "--width", str(width),
                            "--height", str(height), "--spp", "1", "--out", str(Path(tmp) / "x.exr"), "--quiet",
                            "--cache-dir", str(Path(tmp) / "scratch")], check=True, capture_output=True)
            d = json.loads(scene.read_text())
            for m in d["materials"].values():
                if m["bsdf"].get("type") == "tabulated":
                    m["bsdf"]["method"] = "pfmc"
            scene.write_text(json.dumps(d))
            args[args.index("snake")] = str(scene)
        env = dict(os.environ, BSDFLAB_CACHE_DIR=str(cache))
        start = time.perf_counter()
        done = subprocess.run(args, capture_output=True, text=True, env=env)
        wall = time.perf_counter() - start
        if done.returncode != 0:
            raise SystemExit(done.stderr)
        summary = json.loads(done.stdout[done.stdout.index("{"):done.stdout.rindex("}") + 1])
        print(f"{method}: wall {wall:.1f} s, render_seconds {summary['render_seconds']}", flush=True)
        from bsdflab.tables import read_table

        tables = [read_table(p) for p in sorted(cache.glob("*.exr"))]
    table_s = sum(t.meta.get("seconds", 0.0) for t in tables)
    render_s = float(summary["render_seconds"])
    return {"method": ", ".join(t.meta.get("method", "pfmc") for t in tables), "wall": wall, "table": table_s,
            "render": render_s, "build": wall - table_s - render_s,
            "p95": [t.accuracy()["p95"] for t in tables]}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--width", type=int, default=1280)
    p.add_argument("--height", type=int, default=720)
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--method", choices=("auto", "pfmc", "both"), default="auto")
    args = p.parse_args()
    methods = ("auto", "pfmc") if args.method == "both" else (args.method,)
    print(f"bsdflab render snake --width {args.width} --height {args.height} --spp {args.spp}, empty cache, "
          f"BSDFLAB_THREADS={os.environ.get('BSDFLAB_THREADS', 'all')}, load {os.getloadavg()[0]:.1f}")
    rows = {m: run(args.width, args.height, args.spp, m) for m in methods}
    for m, r in rows.items():
        p95 = ", ".join(f"{x:.3g}" for x in r["p95"])
        print(f"{m:<5} table by {r['method']:<16} table {r['table']:6.1f} s  build {r['build']:5.1f} s  "
              f"render {r['render']:6.1f} s  wall {r['wall']:6.1f} s  (table p95 {p95})")
    if len(rows) == 2:
        print(f"first-use table: pfmc / auto = {rows['pfmc']['table'] / rows['auto']['table']:.1f}x")


if __name__ == "__main__":
    main()
