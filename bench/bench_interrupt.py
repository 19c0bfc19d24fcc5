"""How long `bsdflab render` and `bsdflab fit` take to exit after Ctrl-C (SIGINT), in wall
seconds and in the process's own CPU seconds after the signal.

The CPU seconds are what the code controls (how often it looks at the flag, what it tears
down); the wall seconds are those CPU seconds stretched by the machine's load (a process
gets about cores / runnable of a core). Each run waits until the work is under way (the
progress bar, then one CPU-second more), sends SIGINT once, and reads the child's total
CPU time from wait4's rusage.

    python bench/bench_interrupt.py --runs 4          # under the load the machine has
    stress --cpu 2 & python bench/bench_interrupt.py  # under a deliberate load
"""
from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from support.cli import BSDFLAB, _default_sigint, cpu_seconds  # noqa: E402  (the tests' helpers)


def interrupt_once(args: list[str], marker: str, env: dict) -> tuple[float, float, int]:
    """(wall s, CPU s after the signal, exit status) of one interrupted run."""
    proc = subprocess.Popen(args, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, env=env,
                            preexec_fn=_default_sigint)
    seen = b""
    while marker.encode() not in seen[-4096:]:
        chunk = proc.stderr.read1(256)
        if not chunk:
            raise RuntimeError(f"ended before {marker!r}: {seen[-2000:].decode(errors='replace')}")
        seen += chunk
    target = cpu_seconds(proc.pid) + 1.0
    while cpu_seconds(proc.pid) < target:  # its work is under way, at any load
        time.sleep(0.02)
    before = cpu_seconds(proc.pid)
    t0 = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    drain = threading.Thread(target=proc.stderr.read, daemon=True)  # a full pipe must not hold it
    drain.start()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    return wall, usage.ru_utime + usage.ru_stime - before, proc.returncode


def fit_args(tmp: Path) -> list[str]:
    """A fit of the shipped example that cannot converge first (tau_multiple 1e9)."""
    cfg = (ROOT / "examples/fit/fit.toml").read_text().replace("tau_multiple = 50", "tau_multiple = 1e9") \
        .replace("max_steps = 6000", "max_steps = 1000000")
    (tmp / "fit.toml").write_text(cfg)
    return [*BSDFLAB, "fit", str(ROOT / "examples/fit/data.csv"), "--config", str(tmp / "fit.toml"),
            "--out", str(tmp / "study")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=4)
    a = ap.parse_args()
    env = {**os.environ, "BSDFLAB_MAX_SPP": str(2**28)}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        cases = {
            "render (furnace 64x64, 2^28 spp)": ([*BSDFLAB, "render", "furnace", "--width", "64", "--height", "64",
                                                  "--spp", str(2**28), "--out", str(tmp / "r.exr")], "rendering"),
            "fit (examples/fit, never converges)": (fit_args(tmp), "it/s"),
        }
        print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
        for name, (args, marker) in cases.items():
            rows = [interrupt_once(args, marker, env) for _ in range(a.runs)]
            walls, cpus = [r[0] for r in rows], [r[1] for r in rows]
            print(f"{name}: exit {sorted({r[2] for r in rows})}; wall s min/median/max "
                  f"{min(walls):.2f}/{statistics.median(walls):.2f}/{max(walls):.2f}; CPU s after the signal "
                  f"{min(cpus):.2f}/{statistics.median(cpus):.2f}/{max(cpus):.2f}")
        print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
