"""The vectorised core gives identical answers on 1 thread and on all threads.

The script asks for the 81 default wavelengths explicitly (no RGB weights) and gives the
diffuse reflectance as a tabulated spectrum, not RGB: the core does the same work, but the
process no longer imports ``colour`` for the sRGB weights (~2.4 CPU-s of each process's
~3.5; the RGB conversion is numpy after the core, one thread). 50 000 rows: 2 threads split
each call. 8.1 -> 3.4 CPU-s. Mutation: BSDF.eval scaled by 1 + 1e-12 x the core's worker
count fails it."""
import os
import subprocess
import sys

SCRIPT = """
import numpy as np, bsdflab as bl
from bsdflab.spectra import DEFAULT_WAVELENGTHS as WL
rng = np.random.default_rng(7)
v = rng.normal(size=(50000, 3)); v /= np.linalg.norm(v, axis=1, keepdims=True)
w = rng.normal(size=(50000, 3)); w /= np.linalg.norm(w, axis=1, keepdims=True)
out = []
rho = {{'type': 'tabulated', 'wavelengths': [400.0, 550.0, 700.0], 'values': [0.2, 0.5, 0.7]}}
for m in (bl.Diffuse(rho), bl.Conductor(material='Au'), bl.Dielectric(1.5, 1.0)):
    s = m.sample(v, seed=3, wavelengths=WL)
    out += [m.eval(v, w, wavelengths=WL), m.pdf(v, w, wavelengths=WL), s.wo, s.weight, s.pdf]
assert 'colour' not in __import__('sys').modules
np.save({path!r}, np.concatenate([np.ravel(a) for a in out]))
"""


def test_01_one_thread_equals_many(tmp_path):
    results = []
    for threads in ("1", "2"):
        path = tmp_path / f"t{threads}.npy"
        env = dict(os.environ, BSDFLAB_THREADS=threads)
        subprocess.run([sys.executable, "-c", SCRIPT.format(path=str(path))], check=True, env=env,
                       timeout=120)
        results.append(path.read_bytes())
    assert results[0] == results[1]
