"""Are the core's estimates bit-identical when it is built by another compiler?

Builds the C++ core a second time with ``--compiler`` (default clang++; Debian: ``apt-get
install clang``) into ``--build-dir``, then runs the same battery with the installed core
(GCC, from ``./dev.sh setup``) and with that build, each in a fresh process, and compares
every output bit for bit. The battery: PFMC estimates (value and standard error) of the
snake preset at 81 wavelengths and of a thick bright slab, ``sample()`` draws and their
weights, ``pdf()``, and a rough film-coated interface's eval. CMakeLists.txt builds with
-ffp-contract=off so that no compiler fuses multiply-adds differently; libm's exp/sincos
are the same library for both builds.

Not a test (it builds the core, minutes): run it after changing the estimator.
Power: ``--cxx-flags=-ffast-math`` (reassociation) must report DIFFERENT; on x86-64's
baseline (no FMA) a missing -ffp-contract=off would not show, on aarch64 it would.
Run: python bench/compiler_identity.py [--compiler clang++] [--build-dir /tmp/bsdflab-clang]
     [--cxx-flags=...]
"""
from __future__ import annotations

import argparse
import glob
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

BATTERY = r'''
import importlib.util, sys
import numpy as np
core_path, out = sys.argv[1], sys.argv[2]
if core_path != "-":
    spec = importlib.util.spec_from_file_location("bsdflab._core", core_path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["bsdflab._core"] = mod
    spec.loader.exec_module(mod)
import bsdflab as bl
from bsdflab.spectra import DEFAULT_WAVELENGTHS
from bsdflab.testing import random_unit_vectors
import bsdflab._core as core_module
res = {}
wi = random_unit_vectors(16, seed=1, hemisphere="upper")
wo = random_unit_vectors(16, seed=2, hemisphere="upper")
snake = bl.presets.xenopeltis()._core(DEFAULT_WAVELENGTHS)
v, e, nonfinite, _ = snake.estimate(wi, wo, int(bl.Lobe.ALL), None, 256, 7)
res["snake_value"], res["snake_err"] = v, e
snake2 = bl.presets.xenopeltis()
snake2.estimator = "pfmc2"
res["snake_pfmc2"] = snake2.eval(wi, wo, wavelengths=DEFAULT_WAVELENGTHS)
slab = bl.Layered([bl.Dielectric(1.5)], [bl.Slab(thickness_um=10.0, sigma_a=0.001, sigma_s=0.999,
                  phase={"type": "hg", "g": 0.3})], bl.Diffuse(0.8), samples=64)
res["slab_eval"] = slab.eval(wi, wo, wavelengths=[450.0, 550.0, 650.0])
m = bl.presets.xenopeltis(samples=32)
s = m.sample(np.repeat(wi[:1], 64, axis=0), seed=3, wavelengths=[450.0, 550.0, 650.0])
res["sample_wo"], res["sample_weight"], res["sample_pdf"] = np.asarray(s.wo), np.asarray(s.weight), np.asarray(s.pdf)
res["pdf"] = m.pdf(wi, wo, wavelengths=[450.0, 550.0, 650.0])
top = bl.RoughDielectric(0.08, int_ior=1.55, film=[{"material": 1.83, "thickness_nm": 400.0}])
res["film_eval"] = top.eval(wi, wo, wavelengths=DEFAULT_WAVELENGTHS)
np.savez(out, **{k: np.asarray(x) for k, x in res.items() })
print("core:", core_module.__file__)
'''


def build(compiler: str, build_dir: Path, cxx_flags: str = "") -> Path:
    try:
        import pybind11  # a build requirement (pyproject's build-system), not a runtime one
    except ImportError:
        raise SystemExit("needs pybind11 in this environment: pip install 'pybind11>=2.12'") from None

    cmake = ["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
             f"-DCMAKE_CXX_COMPILER={compiler}", f"-DPython_EXECUTABLE={sys.executable}",
             f"-Dpybind11_DIR={pybind11.get_cmake_dir()}", f"-DCMAKE_CXX_FLAGS={cxx_flags}"]
    subprocess.run(cmake, check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", str(build_dir), "-j", str(os.cpu_count() or 1)], check=True,
                   stdout=subprocess.DEVNULL)
    found = glob.glob(str(build_dir / "_core*.so"))
    if not found:
        raise SystemExit(f"no _core*.so in {build_dir}")
    return Path(found[0])


def run_battery(core: str, out: Path) -> dict[str, np.ndarray]:
    subprocess.run([sys.executable, "-c", BATTERY, core, str(out)], check=True)
    with np.load(out) as z:
        return {k: z[k] for k in z.files}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--compiler", default="clang++")
    ap.add_argument("--build-dir", default="/tmp/bsdflab-clang", type=Path)
    ap.add_argument("--cxx-flags", default="",
                    help="extra flags for the other build (power check: -ffast-math must differ)")
    args = ap.parse_args()
    other = build(args.compiler, args.build_dir, args.cxx_flags)
    with tempfile.TemporaryDirectory() as tmp:
        a = run_battery("-", Path(tmp) / "installed.npz")
        b = run_battery(str(other), Path(tmp) / "other.npz")
    same = True
    for k in a:
        equal = a[k].shape == b[k].shape and np.array_equal(a[k].view(np.uint8), b[k].view(np.uint8))
        same &= equal
        worst = "" if equal else f"  max |diff| {np.nanmax(np.abs(a[k] - b[k])):.3g}"
        print(f"{k:14s} {a[k].size:6d} numbers  {'bit-identical' if equal else 'DIFFERENT'}{worst}")
    print(f"installed core vs {args.compiler} build: {'bit-identical' if same else 'NOT bit-identical'}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
