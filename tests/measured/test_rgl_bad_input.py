"""Bad RGL and MERL files: a ValueError naming the field, never a crash (hand-built cases,
then hypothesis fuzzing of truncations, byte flips and field edits)."""
from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bsdflab.measured import Measured, Merl
from bsdflab.measured.merl import DIMS, merl_bytes, read_merl
from bsdflab.measured.rgl_file import check_fields
from bsdflab.measured.tensor_file import parse_tensor_file, tensor_file_bytes


def minimal_fields(n_theta=2, n_phi=1, n=2, spectral=False):
    """The smallest valid isotropic file: 2 x 2 grids, constant densities."""
    c = 3 if not spectral else 4
    f = {"description": "minimal", "jacobian": np.array([1], np.uint8),
         "theta_i": np.linspace(0, 1.2, n_theta).astype(np.float32),
         "phi_i": np.linspace(0, 1, n_phi).astype(np.float32),
         "ndf": np.ones((2, 2), np.float32), "sigma": np.ones((2, 2), np.float32),
         "vndf": np.ones((n_phi, n_theta, 2, 2), np.float32),
         "luminance": np.ones((n_phi, n_theta, n, n), np.float32)}
    values = np.full((n_phi, n_theta, c, n, n), 0.5, np.float32)
    if spectral:
        f["spectra"], f["wavelengths"] = values, np.linspace(400, 700, c).astype(np.float32)
    else:
        f["rgb"] = values
    return f


def _write(tmp_path, fields, name="m.bsdf"):
    path = tmp_path / name
    path.write_bytes(tensor_file_bytes(fields))
    return path


def test_minimal_file_reads(tmp_path):
    for spectral in (False, True):
        m = Measured(_write(tmp_path, minimal_fields(spectral=spectral)))
        v = m.eval([[0, 0, 1.0]], [[0.3, 0, np.sqrt(1 - 0.09)]])
        assert np.all(np.isfinite(v)) and np.all(v > 0)


def test_tensor_round_trip():
    fields = minimal_fields()
    back = parse_tensor_file(tensor_file_bytes(fields))
    for k, v in fields.items():
        expect = np.frombuffer(v.encode(), np.uint8) if isinstance(v, str) else v
        assert back[k].dtype == expect.dtype and np.array_equal(back[k], expect)


@pytest.mark.parametrize("edit, field", [
    (lambda f: f.pop("vndf"), "vndf"),
    (lambda f: f.pop("rgb"), "rgb"),
    (lambda f: f.__setitem__("ndf", f["ndf"].astype(np.float64)), "ndf"),
    (lambda f: f.__setitem__("theta_i", np.array([0.5, 0.1], np.float32)), "theta_i"),
    (lambda f: f.__setitem__("phi_i", np.linspace(0, 6, 4).astype(np.float32)), "phi_i"),
    (lambda f: f.__setitem__("luminance", np.ones((1, 3, 2, 2), np.float32)), "luminance"),
    (lambda f: f.__setitem__("rgb", np.ones((1, 2, 3, 3, 3), np.float32)), "rgb"),
    (lambda f: f["sigma"].__setitem__((0, 0), np.nan), "sigma"),
    (lambda f: f["vndf"].__setitem__((0, 0, 0, 0), -1.0), "vndf"),
    (lambda f: f.__setitem__("vndf", np.zeros((1, 2, 2, 2), np.float32)), "vndf"),
    (lambda f: f.__setitem__("jacobian", np.array([7], np.uint8)), "jacobian"),
    (lambda f: f.__setitem__("sigma", np.zeros((2, 2), np.float32)), "sigma"),
])
def test_bad_fields_name_the_field(tmp_path, edit, field):
    fields = minimal_fields()
    edit(fields)
    with pytest.raises(ValueError, match=repr(field).replace("'", "'")):
        Measured(_write(tmp_path, fields))


def test_negative_spectra_and_anisotropic(tmp_path):
    f = minimal_fields(spectral=True)
    f["spectra"][0, 0, 0, 0, 0] = -0.1
    with pytest.raises(ValueError, match="'spectra'"):
        Measured(_write(tmp_path, f))
    with pytest.raises(ValueError, match="anisotropic"):
        Measured(_write(tmp_path, minimal_fields(n_phi=5), "aniso.bsdf"))


def test_bad_container(tmp_path):
    good = tensor_file_bytes(minimal_fields())
    cases = {"magic": b"tensor_fila\0" + good[12:], "version": good[:12] + b"\2\0" + good[14:],
             "truncated": good[:-7], "empty": b""}
    for name, data in cases.items():
        path = tmp_path / f"{name}.bsdf"
        path.write_bytes(data)
        with pytest.raises(ValueError):
            Measured(path)
    with pytest.raises(ValueError, match="cannot read"):
        Measured(tmp_path / "missing.bsdf")


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_fuzz_rgl_bytes(data):
    """Any corruption of a valid file: parsed and checked, or a ValueError; nothing else."""
    good = bytearray(tensor_file_bytes(minimal_fields(n=3)))
    kind = data.draw(st.sampled_from(["truncate", "flip", "splice"]))
    if kind == "truncate":
        blob = bytes(good[:data.draw(st.integers(0, len(good)))])
    elif kind == "flip":
        for _ in range(data.draw(st.integers(1, 8))):
            i = data.draw(st.integers(0, len(good) - 1))
            good[i] = data.draw(st.integers(0, 255))
        blob = bytes(good)
    else:
        i = data.draw(st.integers(0, len(good)))
        blob = bytes(good[:i]) + data.draw(st.binary(max_size=64)) + bytes(good[i:])
    try:
        check_fields(parse_tensor_file(blob))
    except ValueError:
        pass


@functools.cache
def good_merl() -> bytes:
    """A valid MERL file (35 MB; 0.26 CPU-s to make: made once, not once per example)."""
    return merl_bytes(np.full((3, *DIMS), 0.01))


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 12 + 8 * 3 * 90 * 90 * 180 + 16), st.integers(0, 255))
def test_fuzz_merl(tmp_path_factory, cut, byte):
    """The file cut at ``cut`` bytes, its byte ``min(cut, size - 1)`` set to ``byte``: a
    ValueError or a read. Mutation: read_merl's length check raising EOFError fails it."""
    good = good_merl()
    blob = bytearray(good[:cut])
    if cut >= len(good):   # the set byte lies inside the kept part only for the whole file
        blob[len(good) - 1] = byte
    blob = bytes(blob)
    path = tmp_path_factory.mktemp("merl") / "f.binary"
    path.write_bytes(blob)
    try:
        read_merl(path)
    except ValueError:
        pass


def test_merl_reads_a_hand_built_file(tmp_path):
    values = np.zeros((3, *DIMS))
    values[:] = np.array([0.2, 0.3, 0.4])[:, None, None, None] / np.pi  # a Lambertian BRDF
    values[0, 0, 0, 0] = -1.0  # an unmeasured cell
    path = tmp_path / "lambert.binary"
    path.write_bytes(merl_bytes(values))
    m = Merl(path)
    wi = np.array([[0.3, 0.1, np.sqrt(0.9)]])
    wo = np.array([[-0.5, 0.2, np.sqrt(0.71)]])
    assert np.allclose(m.eval(wi, wo), np.array([[0.2, 0.3, 0.4]]) / np.pi * wo[0, 2], rtol=1e-6, atol=0)
    s = m.sample(np.tile(wi, (1000, 1)), seed=1)
    assert np.allclose(s.weight, [0.2, 0.3, 0.4], rtol=1e-6, atol=0)  # float32 storage
    rng = np.random.default_rng(2)
    a, b = rng.normal(size=(2, 5000, 3))
    a[:, 2], b[:, 2] = np.abs(a[:, 2]), np.abs(b[:, 2])
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    (tmp_path / "random.binary").write_bytes(merl_bytes(rng.random((3, *DIMS))))
    r = Merl(tmp_path / "random.binary")  # the C++ cell index vs numpy's, cell by cell
    assert np.allclose(r.eval(a, b), r.reference.eval(a, b), rtol=1e-6, atol=0)
    core, P = m.render_core()
    assert core.channels == 3 and P is None
    with pytest.raises(ValueError, match="dimensions"):
        (tmp_path / "bad.binary").write_bytes(np.array([90, 90, 90], "<i4").tobytes())
        Merl(tmp_path / "bad.binary")
    nan = values.copy()
    nan[1, 2, 3, 4] = np.nan
    (tmp_path / "nan.binary").write_bytes(merl_bytes(nan))
    with pytest.raises(ValueError, match="NaN"):
        Merl(tmp_path / "nan.binary")
