"""The vectorised core gives identical answers on 1 thread and on all threads."""
import os
import subprocess
import sys

SCRIPT = """
import numpy as np, bsdflab as bl
rng = np.random.default_rng(7)
v = rng.normal(size=(50000, 3)); v /= np.linalg.norm(v, axis=1, keepdims=True)
w = rng.normal(size=(50000, 3)); w /= np.linalg.norm(w, axis=1, keepdims=True)
out = []
for m in (bl.Diffuse([0.2, 0.5, 0.7]), bl.Conductor(material='Au'), bl.Dielectric(1.5, 1.0)):
    s = m.sample(v, seed=3)
    out += [m.eval(v, w), m.pdf(v, w), s.wo, s.weight, s.pdf]
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
