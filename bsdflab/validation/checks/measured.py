"""Measured files: an RGL .bsdf written by bsdflab's writer (bsdflab.measured.export_model)
read by bsdflab's reader (bsdflab.measured.Measured) and by Mitsuba 3's own ``measured``
plugin, query by query. The model under test is ``{"reader": Measured}``: a reader that
mis-scales the file must fail."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from bsdflab.validation.registry import REGISTRY, Outcome, effort

FLOAT32_REL = 1e-4  # Mitsuba computes in float32: eval and pdf agree to ~1e-5 relative (tests/measured)
OPTIONS = {"n_theta_i": 8, "resolution": 24, "error_points": 4000}


def _reader():
    from bsdflab.measured import Measured

    return {"reader": Measured}


def _relative(a, b) -> float:
    """Largest |a - b| relative to |b|, floored at 1e-3 of b's largest (no blow-up at zeros)."""
    scale = np.maximum(np.abs(b), 1e-3 * np.abs(b).max())
    return float(np.max(np.abs(a - b) / scale))


@REGISTRY.check(
    name="measured/rgl-vs-mitsuba/gold",
    family="measured",
    title="An RGL file bsdflab writes: bsdflab's reader against Mitsuba's measured plugin",
    model="bsdflab.measured.Measured on export_model(RoughConductor(0.25, Au)) (RGB, 8 theta_i, 24^2)",
    reference="Mitsuba 3 measured plugin on the same file (eval and pdf)",
    statistic="largest relative difference of eval and pdf at float32 directions",
    tolerance=f"{FLOAT32_REL:g}: the two readers interpolate the same float32 tables; Mitsuba "
    "computes in float32 (~1e-5 relative), deterministic",
    effort=effort({"pairs": 1000}, {"pairs": 5000}),
    make_model=_reader,
    seed=81,
    requires=("mitsuba",),
)
def _rgl_vs_mitsuba(ctx):
    from bsdflab.bsdfs import RoughConductor
    from bsdflab.measured import export_model
    from bsdflab.measured.rgl import random_pairs
    from bsdflab.reference.mitsuba_calls import query

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "gold.bsdf"
        export_model(RoughConductor(alpha=0.25, material="Au"), path, **OPTIONS)
        ours = ctx.model["reader"](path)
        rng = np.random.default_rng(ctx.seed)
        wi, wo = random_pairs(ours.reference, int(ctx.effort["pairs"]), rng)
        wi, wo = (np.asarray(w, np.float32).astype(np.float64) for w in (wi, wo))
        n = len(wi)
        theirs = query(
            {"type": "measured", "filename": str(path)},
            wi,
            wo,
            rng.random(n),
            rng.random((n, 2)).astype(np.float32).astype(np.float64),
        )
        e, p = _relative(ours.eval(wi, wo), theirs.eval), _relative(ours.pdf(wi, wo), theirs.pdf)
    worst = max(e, p)
    return Outcome(
        worst <= FLOAT32_REL,
        worst,
        FLOAT32_REL,
        "<=",
        f"eval {e:.2e}, pdf {p:.2e} largest relative difference over {n} pairs",
        {"eval": e, "pdf": p, "pairs": n},
    )
