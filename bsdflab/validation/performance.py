"""Performance ratios from the benchmarks in bench/ (each compares against a peer in the
same run and prints ratios): run as subprocesses, their output kept verbatim."""
from __future__ import annotations

import re
import subprocess
import sys
import time

from bsdflab.validation.provenance import REPO

BENCHES = {"quick": (), "standard": ("bench_thin_film.py", "bench_layered.py"),
           "full": ("bench_thin_film.py", "bench_layered.py", "bench_tables.py", "bench_render.py")}
RATIO = re.compile(r"([0-9.]+)\s*x\b")
TIMEOUT_S = 900


def run_benchmarks(level: str, progress: bool = True) -> list[dict]:
    """One record per benchmark of the level: name, output, the lines that state ratios,
    return code, seconds. Quick runs none (the report says so)."""
    records = []
    for name in BENCHES[level]:
        path = REPO / "bench" / name
        if not path.exists():
            records.append({"name": name, "returncode": None, "seconds": 0.0, "ratios": [],
                            "output": "bench/ is not part of this installation (run from a checkout)"})
            continue
        if progress:
            print(f"validate: benchmark {name} ...", file=sys.stderr, flush=True)
        start = time.perf_counter()
        try:
            out = subprocess.run([sys.executable, str(path)], cwd=REPO, capture_output=True, text=True,
                                 timeout=TIMEOUT_S)
            text, code = out.stdout + out.stderr, out.returncode
        except subprocess.TimeoutExpired:
            text, code = f"timed out after {TIMEOUT_S} s", -1
        records.append({"name": name, "returncode": code, "seconds": round(time.perf_counter() - start, 1),
                        "ratios": [line.strip() for line in text.splitlines() if RATIO.search(line)],
                        "output": text[-6000:]})
    return records
