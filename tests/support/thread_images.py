"""Run a rendering snippet in subprocesses with 1 and 2 threads and return the images, for
thread-count-independence tests. `expr` is a Python expression for an (H, W, 3) array,
evaluated with the tests folder importable (``support.*``)."""
from __future__ import annotations

import os
import subprocess
import sys

import numpy as np


def images_per_thread_count(tmp_path, imports: str, expr: str, threads=("1", "2")) -> dict[str, np.ndarray]:
    tests = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    code = (f"import numpy as np, sys; sys.path.insert(0, {tests!r}); {imports}; "
            f"np.save(sys.argv[1], {expr})")
    out = {}
    for n in threads:
        path = tmp_path / f"t{n}.npy"
        subprocess.run([sys.executable, "-c", code, str(path)], check=True, env=dict(os.environ, BSDFLAB_THREADS=n))
        out[n] = np.load(path)
    return out
