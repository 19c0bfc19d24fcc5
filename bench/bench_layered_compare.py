"""Layered estimators side by side, in one run: efficiency against today's PFMC.

Efficiency = 1 / (variance x time): the relative variance of one estimate (of the
configuration's projected output) times the CPU seconds it took (all threads; robust to
other processes on a shared machine), per direction pair, median over the pairs. Every
row is printed as a ratio against the reference column: with --baseline-core, "pfmc"
run by an earlier build of the core (`bench/build_core_at.sh <commit>` builds one; that
is "today's PFMC" when this code changes the core's speed), else this build's "pfmc".
The baseline runs in a child process of this script (`--worker`), on the same pairs and
seeds, so one invocation prints every column.

Configurations: the snake preset (luminance of 81 wavelengths), the scattering cases of
tests/layered/test_layered_vs_adding_doubling.py (mean of their 3 channels), a thick
bright slab (tau 10, albedo 0.99, white base), a rough conductor base under a rough top,
and the three configurations where adversarial reviews found pfmc2's shared chains worst.
With --service: the CPU time of one eval of the preset at 1 % luminance error, and the
wall time of the same eval over HTTP on a real `bsdflab serve` (the baseline's server
runs the baseline core); --tabulate: the snake table (RGB, small grid, equal target error);
--render SECONDS: a direct-PFMC render of the snake (every layered material evaluated by
the walk, no table) with each estimator for the same wall time, mean pixel variance over
the snake's pixels.
Run: python bench/bench_layered_compare.py [--pairs 16] [--walks 2000] [--service] [--tabulate]
     [--render 20] [--baseline-core /tmp/core-v5.so]
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import time


def _load_core(path: str) -> None:
    """Import bsdflab with the compiled core at `path` (an earlier build) instead of its own."""
    spec = importlib.util.spec_from_file_location("bsdflab._core", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["bsdflab._core"] = module
    spec.loader.exec_module(module)


if __name__ == "__main__" and "--core" in sys.argv:  # before bsdflab imports its own core
    _load_core(sys.argv[sys.argv.index("--core") + 1])

import numpy as np  # noqa: E402

import bsdflab as bl  # noqa: E402
from bsdflab import _core  # noqa: E402
from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum, srgb_weights  # noqa: E402
from bsdflab.tables.channels import LUMINANCE_RGB  # noqa: E402
from bsdflab.testing import random_unit_vectors  # noqa: E402

ESTIMATORS = ("pfmc", "pfmc2")
WL3 = [450.0, 550.0, 650.0]


def _slab(tau, albedos, phase=None, thickness=1.0):
    sigma_s = float(np.max(albedos)) * tau / thickness
    sigma_a = sigma_s / np.asarray(albedos, dtype=float) - sigma_s
    return bl.Slab(thickness, sigma_a=Spectrum.tabulated(WL3, sigma_a), sigma_s=sigma_s, phase=phase)


FWD, BACK = {"type": "hg", "g": 0.6}, {"type": "hg", "g": -0.3}
TOP = bl.Dielectric(1.5, 1.0)


def configurations():
    """name -> (layers (interfaces, slabs, base), wavelengths, projection row (C,), transmission)."""
    wl = np.asarray(DEFAULT_WAVELENGTHS, dtype=float)
    lum = LUMINANCE_RGB @ srgb_weights(wl)
    mean3 = np.full(3, 1.0 / 3.0)
    snake = bl.presets.xenopeltis()
    rough_top = bl.RoughDielectric(0.3, int_ior=1.5, ext_ior=1.0)
    return {
        "snake (xenopeltis, Y)": ((snake.interfaces, snake.slabs, snake.base), wl, lum, False),
        "iso tau1 w.5-.9 lambert": (([TOP], [_slab(1.0, [0.5, 0.7, 0.9])], bl.Diffuse(0.5)), WL3, mean3, False),
        "hg.6 tau5 w.9-.99 black": (([TOP], [_slab(5.0, [0.9, 0.95, 0.99], FWD)], bl.Diffuse(0.0)), WL3, mean3,
                                    False),
        "hg-.3 tau.5 w.5-.95 lambert": (([TOP], [_slab(0.5, [0.5, 0.8, 0.95], BACK)], bl.Diffuse(0.8)), WL3,
                                        mean3, False),
        "hg.6 tau2 w.7-.99 glass (T)": (([TOP], [_slab(2.0, [0.7, 0.9, 0.99], FWD)], bl.Dielectric(1.0, 1.5)),
                                        WL3, mean3, True),
        "iso tau3 matched (T)": (([bl.Dielectric(1.5, 1.5)], [_slab(3.0, [0.5, 0.9, 0.99])],
                                  bl.Dielectric(1.5, 1.5)), WL3, mean3, True),
        "thick bright tau10 w.99": (([TOP], [_slab(10.0, [0.99, 0.99, 0.99])], bl.Diffuse(1.0)), WL3, mean3,
                                    False),
        "rough conductor base": (([rough_top], [_slab(1.0, [0.6, 0.8, 0.95], FWD)],
                                  bl.RoughConductor(0.2, eta=0.2, k=3.0, ext_ior=1.5)), WL3, mean3, False),
        # The adversarial review's worst cases for shared light chains (a wide exit lobe).
        "rough .8 top, clear slab": (([bl.RoughDielectric(0.8, int_ior=1.5)], [bl.Slab(0.1)], bl.Diffuse(0.5)),
                                     WL3, mean3, False),
        "rough .5 top, rough gold": (([bl.RoughDielectric(0.5, int_ior=1.5)], [_slab(0.2, [0.8, 0.9, 0.95])],
                                      bl.RoughConductor(0.3, eta=0.18, k=3.1, ext_ior=1.5)), WL3, mean3, False),
        # ... and the second review's: a wide interior boundary under a narrow top.
        "top .1, interior .8": (([bl.RoughDielectric(0.1, 1.5), bl.RoughDielectric(0.8, 1.3, 1.5)],
                                 [bl.Slab(0.3, sigma_a=0.3, sigma_s=0.5)] * 2, bl.Diffuse(0.8)), WL3, mean3, False),
    }


def efficiency(core, wi, wo, walks, row, repeats):
    """(efficiency, CPU seconds per pair, relative variance per walk): medians over pairs."""
    best = np.inf
    for _ in range(repeats):
        t0 = time.process_time()  # CPU seconds of all threads: robust to other processes' load
        value, err, bad, capped = core.estimate(wi, wo, int(bl.Lobe.ALL), None, walks, 7)
        best = min(best, time.process_time() - t0)
    assert bad == 0 and capped == 0
    mean, se = value @ row, err @ np.abs(row)
    ok = mean > 0
    rel_var = (se[ok] / mean[ok]) ** 2
    return 1.0 / (np.median(rel_var) * best / len(wi)), best / len(wi), float(np.median(rel_var) * walks)


def per_configuration(est, pairs, walks, repeats):
    out = {}
    for name, ((ifs, slabs, base), wl, row, transmit) in configurations().items():
        wi = random_unit_vectors(pairs, seed=11, hemisphere="upper")
        wo = random_unit_vectors(pairs, seed=12, hemisphere="upper")
        if transmit:
            wo[pairs // 2:, 2] *= -1.0
        core = bl.Layered(list(ifs), list(slabs), base, estimator=est)._core(np.asarray(wl, dtype=float))
        eff, sec, var = efficiency(core, wi, wo, walks, row, repeats)
        out[name] = {"efficiency": eff, "us_per_walk": 1e6 * sec / walks, "relvar_per_walk": var}
    return out


def time_to_one_percent(est, pairs):
    """CPU seconds per pair for a 1 % luminance error on the snake (walks from a pilot run):
    what an eval of the preset at that error costs the service."""
    m = bl.presets.xenopeltis(samples=256)
    wl = np.asarray(DEFAULT_WAVELENGTHS, dtype=float)
    lum = LUMINANCE_RGB @ srgb_weights(wl)
    core = bl.Layered(list(m.interfaces), list(m.slabs), m.base, estimator=est)._core(wl)
    wi = random_unit_vectors(pairs, seed=21, hemisphere="upper")
    wo = random_unit_vectors(pairs, seed=22, hemisphere="upper")
    _, _, rv = efficiency(core, wi, wo, 1000, lum, 1)
    walks = int(np.ceil(rv / 1e-4))
    t0 = time.process_time()
    value, err, _, _ = core.estimate(wi, wo, int(bl.Lobe.ALL), None, walks, 9)
    dt = (time.process_time() - t0) / pairs
    rel = float(np.median((err @ np.abs(lum)) / (value @ lum)))
    return {"walks": walks, "cpu_ms": 1e3 * dt, "reached": rel}


def tabulate_snake(est, rel_error=0.02):
    """CPU seconds of a snake table (RGB) on a small grid with two film-thickness nodes."""
    from bsdflab.tables import TableGrid, tabulate
    m0 = bl.presets.xenopeltis()
    m = bl.Layered(list(m0.interfaces), list(m0.slabs), m0.base, estimator=est)
    t0 = time.process_time()
    table = tabulate(m, TableGrid(4, 8, 5, thickness_nm=(350.0, 450.0)), rel_error=rel_error, progress=False)
    return {"cpu_s": time.process_time() - t0, "walks": int(table.samples.sum()),
            "rms": float(table.meta["rel_error_rms"])}


def render_snake(est, seconds, width=96, height=54):
    """Direct-PFMC snake render for `seconds` of wall time: mean pixel variance on the snake."""
    import dataclasses

    from bsdflab.render import render
    from bsdflab.scenes import scene
    sc = scene("snake", material="direct", width=width, height=height)
    materials = {name: (dataclasses.replace(m, bsdf={**m.bsdf, "estimator": est})
                        if m.bsdf.get("type") == "layered" else m) for name, m in sc.materials.items()}
    sc = dataclasses.replace(sc, materials=materials)
    probe = render(sc, spp=4, seed=2, progress=False)
    spp = max(4, round(seconds / (probe.seconds / probe.spp)))
    r = render(sc, spp=spp, seed=3, progress=False, aovs=True)
    ids = [i for i, sh in enumerate(sc.shapes) if sh.name in ("body", "head")]
    var = float(np.mean(r.variance[np.isin(r.aovs["mesh_id"], ids)]))
    return {"spp": spp, "seconds": r.seconds, "variance": var, "efficiency": 1.0 / (var * r.seconds)}


SITECUSTOMIZE = """import importlib.util, os, sys
path = os.environ.get("BSDFLAB_BENCH_CORE")
if path:  # the benchmark's baseline: an earlier build of the core, loaded before bsdflab's own
    spec = importlib.util.spec_from_file_location("bsdflab._core", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["bsdflab._core"] = module
    spec.loader.exec_module(module)
"""


def http_latency(est, walks, core=None, requests=12, pairs=16):
    """Median wall ms of POST /v1/bsdf/eval on a real `bsdflab serve` (on `core` if given):
    the snake with `est`, `pairs` outgoing angles, `walks` per pair (RGB, through 81 λ)."""
    import tempfile
    from pathlib import Path

    import httpx2 as httpx
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from support.service_process import ServiceProcess
    model = {**bl.presets.xenopeltis().to_dict(), "estimator": est}
    body = {"model": model, "theta_i": [30.0], "theta_o": list(np.linspace(5.0, 85.0, pairs)), "samples": walks}
    with tempfile.TemporaryDirectory() as data:
        env = {}
        if core:
            (Path(data) / "site").mkdir()
            (Path(data) / "site" / "sitecustomize.py").write_text(SITECUSTOMIZE)
            env = {"BSDFLAB_BENCH_CORE": core,
                   "PYTHONPATH": os.pathsep.join([str(Path(data) / "site"), os.environ.get("PYTHONPATH", "")])}
        server = ServiceProcess(Path(data), workers=1, env=env)
        try:
            with httpx.Client(base_url=server.url, timeout=120) as client:
                times = []
                for _ in range(requests + 2):
                    t0 = time.perf_counter()
                    r = client.post("/v1/bsdf/eval", json=body)
                    times.append(time.perf_counter() - t0)
                    assert r.status_code == 200, r.text
        finally:
            server.stop()
    return {"ms": 1e3 * float(np.median(times[2:])), "walks": walks}


def measure(estimators, args):
    res = {est: {"configurations": per_configuration(est, args.pairs, args.walks, args.repeats)}
           for est in estimators}
    for est in estimators:
        if args.service:
            res[est]["service"] = time_to_one_percent(est, args.pairs)
            # The walks that reach 1 % by the error just measured: a request's fixed cost
            # (JSON, HTTP) does not scale with walks, so the latency is compared as it is.
            s = res[est]["service"]
            res[est]["http"] = http_latency(est, int(np.ceil(s["walks"] * (s["reached"] / 0.01) ** 2)), args.core)
        if args.tabulate:
            res[est]["tabulate"] = tabulate_snake(est)
        if args.render:
            res[est]["render"] = render_snake(est, args.render)
    return res


def baseline(args):
    """Today's PFMC: this script in a child process on the earlier core."""
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--core", args.baseline_core,
           "--pairs", str(args.pairs), "--walks", str(args.walks), "--repeats", str(args.repeats)]
    cmd += ["--service"] * args.service + ["--tabulate"] * args.tabulate
    cmd += ["--render", str(args.render)] if args.render else []
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])["pfmc"]


def report(res, ref):
    cols = list(res)
    print(f"efficiency against {ref!r} (> 1: reaches an error in less CPU time); CPU-us per walk; "
          "relative variance per walk")
    print(f"  {'configuration':28s} " + " ".join(f"{c:>26s}" for c in cols))
    for name in res[ref]["configurations"]:
        cells = []
        for c in cols:
            r, r0 = res[c]["configurations"][name], res[ref]["configurations"][name]
            cells.append(f"{r['efficiency'] / r0['efficiency']:5.2f}x {r['us_per_walk']:7.2f}us "
                         f"{r['relvar_per_walk']:8.3g}")
        print(f"  {name:28s} " + " ".join(f"{s:>26s}" for s in cells))
    for key, title, line, cost in SECTIONS:
        if key not in res[ref]:
            continue
        print(title)
        for c in cols:
            ratio = cost(res[ref][key], res[ref]) / cost(res[c][key], res[c])
            print(f"  {c:26s} {line(res[c][key])}  {ratio:5.2f}x at equal error")


# The extra measurements: key, title, one row's text, and its cost (time x squared error,
# or time at equal error; the ratio printed is the reference's cost over the row's).
# Arguments: the section's result and the column's whole result.
SECTIONS = [
    ("service", "snake, 1 % relative luminance error per pair (walks from a pilot run), CPU-ms per pair:",
     lambda s: f"{s['walks']:6d} walks {s['cpu_ms']:8.2f} ms (reached {100 * s['reached']:.2f} %)",
     lambda s, col: s["cpu_ms"] * s["reached"] ** 2),
    ("http", "1 % over HTTP (walks rescaled by the error reached above): POST /v1/bsdf/eval on a real "
             "`bsdflab serve`, 16 pairs, median wall ms:",
     lambda h: f"{h['walks']:6d} walks {h['ms']:8.1f} ms",
     lambda h, col: h["ms"]),
    ("tabulate", "snake table (RGB, 4 x 8 x 5 x 2 thickness nodes, 2 % target), CPU seconds:",
     lambda t: f"{t['cpu_s']:7.1f} CPU-s {t['walks']:9d} walks  rms {t['rms']:.4f}",
     lambda t, col: t["cpu_s"] * t["rms"] ** 2),
    ("render", "direct-PFMC snake render at equal wall time (96 x 54), mean pixel variance on the snake:",
     lambda r: f"{r['spp']:6d} spp in {r['seconds']:6.1f} s, variance {r['variance']:.4e}",
     lambda r, col: r["seconds"] * r["variance"]),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", type=int, default=16)
    ap.add_argument("--walks", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--tabulate", action="store_true", help="also time the snake table")
    ap.add_argument("--service", action="store_true", help="also time 1 %% luminance evals of the preset")
    ap.add_argument("--render", type=float, default=0.0, help="direct-PFMC render, wall seconds per estimator")
    ap.add_argument("--baseline-core", help="an earlier build's _core*.so: its pfmc is the reference")
    ap.add_argument("--core", help=argparse.SUPPRESS)  # used by the child process
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(measure(["pfmc"], args)))
        return
    print(f"{_core.worker_count()} threads, {args.pairs} pairs, {args.walks} walks per pair, best of "
          f"{args.repeats}; load average {os.getloadavg()[0]:.1f} at start")
    res = {}
    if args.baseline_core:
        res["pfmc, baseline core"] = baseline(args)
    res.update(measure(ESTIMATORS, args))
    report(res, "pfmc, baseline core" if args.baseline_core else "pfmc")


if __name__ == "__main__":
    main()
