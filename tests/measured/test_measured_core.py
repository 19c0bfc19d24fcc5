"""bl.Measured's C++ core against the numpy statement of the format (rgl_reference.py):
the same file, the same float32 tables, double arithmetic in both, so eval, pdf and
sampled directions agree to ~1e-9 relative (TOL = 1e-7 leaves room for the order of
operations); and the BSDF interface's promises (zero below the surface, NaN-proof)."""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.bsdfs import RoughConductor
from bsdflab.lobes import Lobe
from bsdflab.measured import Measured, export_model
from bsdflab.measured.rgl import random_pairs
from bsdflab.testing import eval_pdf_consistency

TOL = 1e-7


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rgl")
    model = RoughConductor(alpha=0.15, material="Cu")
    export_model(model, folder / "cu.bsdf", n_theta_i=6, resolution=16, error_points=500)
    export_model(model, folder / "cu_spec.bsdf", wavelengths=[450.0, 550.0, 650.0], n_theta_i=6,
                 resolution=16, error_points=500)
    return folder / "cu.bsdf", folder / "cu_spec.bsdf"


def _rel(a, b):
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-6 * np.abs(b).max())))


@pytest.mark.parametrize("which", [0, 1])
def test_core_matches_numpy(files, which):
    m = Measured(files[which])
    rng = np.random.default_rng(4)
    wi, wo = random_pairs(m.reference, 3000, rng)
    channels = m.data.wavelengths.astype(float) if m.spectral else None
    assert _rel(m.eval(wi, wo, wavelengths=channels), m.reference.eval(wi, wo)) < TOL
    assert _rel(m.pdf(wi, wo), m.reference.pdf(wi, wo)) < TOL
    u = rng.random((3000, 2))
    s = m.sample(wi, np.zeros(3000), u, wavelengths=channels)
    wo_r, w_r, pdf_r = m.reference.sample(wi, u)
    ok = pdf_r > 0
    assert np.array_equal(s.pdf > 0, ok)
    assert np.abs(s.wo[ok] - wo_r[ok]).max() < 1e-9
    assert _rel(s.pdf[ok], pdf_r[ok]) < TOL and _rel(s.weight[ok], w_r[ok]) < TOL
    assert set(np.unique(s.lobe[ok])) == {int(Lobe.GLOSSY_REFLECTION)}


def test_interface_promises(files):
    m = Measured(files[0])
    up = np.array([[0.3, 0.1, np.sqrt(0.9)]])
    down = up * [1, 1, -1]
    assert np.all(m.eval(up, down) == 0) and np.all(m.eval(down, up) == 0) and np.all(m.pdf(down, up) == 0)
    assert np.all(m.eval(up, up, lobes=Lobe.DIFFUSE) == 0)
    core = m._core(np.array([0.0, 1.0, 2.0]))
    bad = np.array([[np.nan, 0, 1.0], [0, 0, 0.0], [0, 0, 1.0]])
    assert np.all(np.isfinite(core.eval(bad, bad[::-1], int(Lobe.ALL), None)))
    report = eval_pdf_consistency(m, [0.5, 0.0, np.sqrt(0.75)], n=50_000)
    assert report.checked > 40_000
    # sample() then pdf() round-trips the warp (a quadratic root and its inverse): ~1e-8
    assert report.max_weight_error < 1e-6 and report.max_pdf_error < 1e-6


def test_dict_form(files):
    from bsdflab.bsdfs import from_dict

    m = Measured(files[0])
    assert from_dict(m.to_dict()) == m and m.to_dict() == {"type": "measured", "path": str(files[0])}


def test_render_cores(files):
    rgb, spectral = Measured(files[0]), Measured(files[1])
    core, P = rgb.render_core()
    assert core.channels == 3 and P is None
    core, P = spectral.render_core()
    assert core.channels == 81 and P.shape == (3, 81)
    with pytest.raises(ValueError, match="RGB"):
        rgb._core(np.array([550.0]))
