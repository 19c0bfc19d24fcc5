"""The snake's direct evaluation for profilers (bench/README.md, "Profiling the layered walk").

The xenopeltis preset through 81 wavelengths, 16 direction pairs x `--walks` walks with the
chosen estimator; prints CPU-microseconds per walk (steadier than wall time on a loaded
machine). One thread gives the cleanest profile: BSDFLAB_THREADS=1.

    python bench/profile_layered.py [--estimator pfmc2] [--walks 4000]
"""
from __future__ import annotations

import argparse
import time


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--estimator", default="pfmc2", choices=("pfmc", "pfmc2"))
    ap.add_argument("--walks", type=int, default=4000)
    args = ap.parse_args()

    import numpy as np

    import bsdflab as bl
    from bsdflab.spectra import DEFAULT_WAVELENGTHS
    from bsdflab.testing import random_unit_vectors

    m = bl.presets.xenopeltis()
    core = bl.Layered(list(m.interfaces), list(m.slabs), m.base, estimator=args.estimator)._core(
        np.asarray(DEFAULT_WAVELENGTHS, dtype=float))
    wi = random_unit_vectors(16, seed=11, hemisphere="upper")
    wo = random_unit_vectors(16, seed=12, hemisphere="upper")
    cpu0 = time.process_time()
    core.estimate(wi, wo, int(bl.Lobe.ALL), None, args.walks, 7)
    print(f"{args.estimator}: {1e6 * (time.process_time() - cpu0) / (16 * args.walks):.2f} CPU-us per walk")


if __name__ == "__main__":
    main()
