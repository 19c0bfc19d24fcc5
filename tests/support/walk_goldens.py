"""Golden outputs of the layered PFMC walk (issue 34): eval, pdf, sample, estimate and
eval_with_error of both estimators on a set of stacks at fixed seeds and directions.

A refactor of the walk (core/src/layered/) must leave every number bit-identical; the test
tests/layered/test_walk_goldens.py compares against the committed JSON exactly. Regenerate
only for a deliberate change of the estimator (and say so in the commit):

    python tests/support/walk_goldens.py --write tests/layered/walk_goldens.json

The estimates pass error_walks=0: the goldens pin the walk's own mean and spread (the error
before error_walks pooled extra walks), which the pooled default must leave reproducible.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import tempfile
from pathlib import Path

import numpy as np

import bsdflab as bl
from bsdflab.presets import guanine_film
from bsdflab.spectra import Spectrum

ESTIMATORS = ("pfmc", "pfmc2")
WALKS = 48  # per eval / estimate: enough to visit every event kind, cheap to regenerate
WL3 = [450.0, 550.0, 650.0]
WL8 = [400.0, 440.0, 480.0, 520.0, 560.0, 600.0, 640.0, 680.0]
GOLDENS = Path(__file__).resolve().parents[1] / "layered" / "walk_goldens.json"


def _stacks(estimator: str) -> dict:
    """name -> (model, wavelengths or None for RGB)."""
    kw = dict(samples=WALKS, seed=7, estimator=estimator)
    hg = {"type": "hg", "g": 0.6}
    snake = bl.presets.xenopeltis()
    return {
        "snake": (
            bl.Layered(
                list(snake.interfaces), list(snake.slabs), snake.base, samples=WALKS, seed=3, estimator=estimator
            ),
            None,
        ),
        "rough-top-diffuse": (
            bl.Layered(
                [bl.RoughDielectric(0.3, 1.5, 1.0)], [bl.Slab(1.0, sigma_a=0.2, sigma_s=0.5)], bl.Diffuse(0.8), **kw
            ),
            WL3,
        ),
        "transmissive-rough": (
            bl.Layered(
                [bl.RoughDielectric(0.2, 1.5, 1.0)],
                [bl.Slab(0.5, sigma_a=0.1, sigma_s=1.0)],
                bl.RoughDielectric(0.4, 1.0, 1.5),
                **kw,
            ),
            WL3,
        ),
        "transmissive-smooth": (
            bl.Layered(
                [bl.Dielectric(1.5, 1.0)],
                [bl.Slab(0.7, sigma_a=0.05, sigma_s=2.0, phase=hg)],
                bl.Dielectric(1.0, 1.5),
                **kw,
            ),
            WL3,
        ),
        "film-top": (
            bl.Layered(
                [bl.RoughDielectric(0.15, 1.55, 1.0, film=guanine_film(180.0))],
                [bl.Slab(2.0, sigma_a=0.3, sigma_s=0.4, phase=hg)],
                bl.Diffuse(0.3),
                **kw,
            ),
            WL8,
        ),
        "film-smooth-top": (
            bl.Layered(
                [bl.Dielectric(1.55, 1.0, film=guanine_film(120.0))],
                [bl.Slab(1.0, sigma_a=0.1)],
                bl.Conductor(material="Ag", ext_ior=1.55),
                **kw,
            ),
            WL3,
        ),
        "hg-bright-thick": (
            bl.Layered(
                [bl.RoughDielectric(0.25, 1.5, 1.0)],
                [bl.Slab(3.0, sigma_a=[0.01, 0.5, 2.0], sigma_s=4.0, phase=hg)],
                bl.Diffuse(0.9),
                **kw,
            ),
            WL3,
        ),
        "hg-backward-two-slabs": (
            bl.Layered(
                [bl.RoughDielectric(0.3, 1.5, 1.0), bl.Dielectric(1.3, 1.5)],
                [bl.Slab(0.5, sigma_s=1.0, phase={"type": "hg", "g": -0.4}), bl.Slab(0.5, sigma_a=0.2, sigma_s=0.5)],
                bl.Conductor(material="Au", ext_ior=1.3),
                **kw,
            ),
            WL3,
        ),
        "delta-chain": (
            bl.Layered(
                [bl.Dielectric(1.5, 1.0), bl.Dielectric(1.3, 1.5), bl.Dielectric(1.4, 1.3)],
                [bl.Slab(0.4, sigma_a=0.1), bl.Slab(0.3, sigma_a=0.05, sigma_s=0.8), bl.Slab(0.5, sigma_a=0.2)],
                bl.Conductor(material="Ag", ext_ior=1.4),
                **kw,
            ),
            WL3,
        ),
        "delta-chain-rough-entry": (
            bl.Layered(
                [bl.RoughDielectric(0.3, 1.5, 1.0), bl.Dielectric(1.3, 1.5)],
                [bl.Slab(0.5), bl.Slab(0.5, sigma_a=0.2)],
                bl.Conductor(material="Ag", ext_ior=1.3),
                **kw,
            ),
            WL3,
        ),
        "spectral-absorber": (
            bl.Layered(
                [bl.RoughDielectric(0.2, 1.5, 1.0)],
                [bl.Slab(1.5, sigma_a=Spectrum.tabulated(WL8, [0.0, 0.1, 0.5, 1.0, 2.0, 4.0, 6.0, 8.0]), sigma_s=0.6)],
                bl.Diffuse(0.7),
                **kw,
            ),
            WL8,
        ),
    }


def _directions() -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs: random upper pairs, normal incidence, grazing on either side, and
    pairs below the horizon (transmission, and wi from below)."""
    rng = np.random.default_rng(20340)
    up = rng.normal(size=(8, 3))
    up[:, 2] = np.abs(up[:, 2]) + 0.05
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    wi = list(up[:4])
    wo = list(up[4:])
    g = np.sqrt(1 - 1e-3**2)
    wi += [
        np.array([0.0, 0.0, 1.0]),
        np.array([g, 0.0, 1e-3]),
        up[0],
        np.array([0.6, 0.0, 0.8]),
        np.array([0.3, 0.4, -np.sqrt(0.75)]),
        np.array([0.0, g, -1e-3]),
    ]
    wo += [
        np.array([0.0, 0.0, 1.0]),
        np.array([-0.5, 0.0, np.sqrt(0.75)]),
        np.array([-g, 0.0, 1e-3]),
        np.array([0.0, 0.6, -0.8]),
        up[1] * np.array([1, 1, -1]),
        np.array([0.0, 0.0, 1.0]),
    ]
    return np.array(wi), np.array(wo)


def _floats(a) -> list:
    return np.asarray(a, dtype=np.float64).ravel().tolist()


def generate() -> dict:
    """Every golden value, as plain JSON numbers (repr round-trips float64 exactly)."""
    wi, wo = _directions()
    rng = np.random.default_rng(3401)
    ws = np.tile(wi, (6, 1))  # several draws per direction: sample() is one walk each
    u1, u2 = rng.random(len(ws)), rng.random((len(ws), 2))
    out = {}
    for est in ESTIMATORS:
        for name, (model, wl) in _stacks(est).items():
            e = model.estimate(wi, wo, wavelengths=wl, samples=WALKS, seed=11, error_walks=0)
            scattered = model.estimate(
                wi, wo, wavelengths=wl, samples=WALKS + 1, seed=12, scattered_only=True, error_walks=0
            )
            v, s = model.eval_with_error(wi, wo, wavelengths=wl, error_walks=0)
            smp = model.sample(ws, u1, u2, wavelengths=wl)
            ok = np.asarray(smp.lobe) != 0  # the walks that returned a direction
            out[f"{est}/{name}"] = {
                "eval": _floats(model.eval(wi, wo, wavelengths=wl)),
                "pdf": _floats(model.pdf(wi, wo, wavelengths=wl)),
                "pdf_sampled": _floats(model.pdf(ws[ok], smp.wo[ok], wavelengths=wl)) if ok.any() else [],
                "sample": {
                    "wo": _floats(smp.wo),
                    "weight": _floats(smp.weight),
                    "pdf": _floats(smp.pdf),
                    "lobe": np.asarray(smp.lobe).astype(int).ravel().tolist(),
                    "eta": _floats(smp.eta),
                },
                "estimate": {
                    "value": _floats(e.value),
                    "stderr": _floats(e.stderr),
                    "nonfinite": e.nonfinite,
                    "capped": e.capped,
                },
                "scattered": {"value": _floats(scattered.value), "stderr": _floats(scattered.stderr)},
                "eval_with_error": {"value": _floats(v), "stderr": _floats(s)},
            }
    return out


def digest(goldens: dict) -> str:
    return hashlib.sha256(json.dumps(goldens, sort_keys=True).encode()).hexdigest()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", type=Path, default=None, help="write the JSON here (atomically)")
    args = ap.parse_args()
    goldens = generate()
    # The machine the bits belong to: libmvec's exp (x86-64 glibc) and libm differ in the last
    # bits elsewhere (tests/layered/test_walk_goldens.py).
    doc = {"sha256": digest(goldens), "machine": platform.machine(), "goldens": goldens}
    if args.write is None:
        print(doc["sha256"])
        return
    fd, tmp = tempfile.mkstemp(dir=args.write.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(doc, f, sort_keys=True, indent=0)
    os.chmod(tmp, 0o644)
    os.replace(tmp, args.write)
    print(f"{args.write}: {doc['sha256']}")


if __name__ == "__main__":
    main()
