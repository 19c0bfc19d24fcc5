"""Regression tests for the bad-input findings (issue #16), one (or a few) per finding.

Each failed on the code before the fix (checked by running this file against the previous
commit's bsdflab/ with the tests kept): the failure each one showed is noted beside it.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import OpenEXR
import pytest

import bsdflab as bl
from bsdflab import optics, presets
from bsdflab.util.files import write_atomically
from bsdflab.render import render
from bsdflab.render.image_io import read_exr
from bsdflab.scenes import scene
from bsdflab.tables import TableBSDF, TableData, TableGrid, cache_key, cached_table, read_table, write_table
from bsdflab.tables import file_format, tabulate

BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]
UP = np.array([0.0, 0.0, 1.0])
OBLIQUE = np.array([0.6, 0.0, 0.8])


def cli(*args, timeout=300, env=None):
    return subprocess.run([*BSDFLAB, *args], capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, **(env or {})})


def one_line_error(result, *words):
    """A clean CLI failure: exit 2, one line on stderr naming the problem, no traceback."""
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.returncode == 2, (result.returncode, result.stderr[-2000:])
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr[-2000:]
    for word in words:
        assert word in lines[0], (word, lines[0])


# -- 1. the table cache's key ----------------------------------------------------------------
MODEL = {"type": "diffuse", "reflectance": 0.5}
GRID = TableGrid(3, 5, 4)


def test_01_cache_key_holds_effort_seed_and_estimator(monkeypatch):
    # old: cache_key took no max_samples / seed (TypeError), min_samples only when given
    base = cache_key(MODEL, GRID, 0.01, "rgb")
    assert base == cache_key(MODEL, GRID, 0.01, ("R", "G", "B"), 512, 65536, 0)  # defaults spelled out
    others = {cache_key(MODEL, GRID, 0.01, "rgb", min_samples=16),
              cache_key(MODEL, GRID, 0.01, "rgb", max_samples=16),
              cache_key(MODEL, GRID, 0.01, "rgb", seed=7)}
    assert base not in others and len(others) == 3
    from bsdflab import _core
    monkeypatch.setattr(_core, "estimator_version", 99, raising=False)
    assert cache_key(MODEL, GRID, 0.01, "rgb") != base


def test_01_cached_table_with_another_seed_is_tabulated_again(tmp_path):
    # old: the second request (seed 7) returned the seed-0 table from the cache
    model = bl.Layered([bl.RoughDielectric(0.2, 1.5, 1.0)], [bl.Slab(1.0)], bl.Diffuse(0.5), samples=8)
    grid = TableGrid(2, 2, 2)
    calls = []

    def request(seed):
        def make():
            calls.append(seed)
            return tabulate(model, grid, 0.5, min_samples=8, max_samples=16, seed=seed, progress=False)
        return cached_table(model.to_dict(), grid, 0.5, "rgb", make, directory=tmp_path,
                            min_samples=8, max_samples=16, seed=seed)

    first, _, hit0 = request(0)
    again, _, hit1 = request(0)
    other, _, hit2 = request(7)
    assert (hit0, hit1, hit2) == (False, True, False) and calls == [0, 7]
    assert other.meta["seed"] == 7 and not np.array_equal(first.values, other.values)


def test_01_cache_file_holding_another_table_is_rebuilt(tmp_path, caplog):
    # old: any valid table file under the key's name was returned as the requested table
    table = TableData(MODEL, GRID, ("reflection",), ("R", "G", "B"), False,
                      np.full((1, 1, 3, 5, 4, 3), 0.1, np.float32), np.zeros((1, 1, 3, 5, 4, 3), np.float32),
                      np.ones((1, 1, 3, 5, 4), np.int32), 0.01)
    key = cache_key(MODEL, GRID, 0.01, "rgb")
    wrong = TableData(**{**table.__dict__, "model": {"type": "diffuse", "reflectance": 0.9}})
    write_table(tmp_path / f"{key}.exr", wrong)
    got, _, hit = cached_table(MODEL, GRID, 0.01, "rgb", lambda: table, directory=tmp_path)
    assert not hit and got.model == MODEL and "not the one requested" in caplog.text


def test_01_tabulate_says_when_the_target_is_not_met(tmp_path):
    # old: "from cache yes" was the only hint; no accuracy verdict at all
    model = json.dumps(bl.Layered([bl.RoughDielectric(0.2, 1.5, 1.0)], [bl.Slab(1.0, sigma_s=2.0)],
                                  bl.Diffuse(0.8), samples=8).to_dict())
    out = cli("tabulate", "--json", model, "--theta-i", "2", "--theta-o", "2", "--phi", "2", "--rel-error",
              "0.0001", "--min-samples", "16", "--max-samples", "16", "--quiet", "--cache-dir", str(tmp_path))
    assert out.returncode == 0, out.stderr
    assert "target met    NO" in out.stdout and "does not reach the target" in out.stderr


# -- 2. loading checks meaning, and signatures -----------------------------------------------
def _valid_table():
    return TableData(MODEL, GRID, ("reflection",), ("R", "G", "B"), False,
                     np.full((1, 1, 3, 5, 4, 3), 0.1, np.float32), np.full((1, 1, 3, 5, 4, 3), 0.001, np.float32),
                     np.ones((1, 1, 3, 5, 4), np.int32), 0.01)


def _edit_and_rehash(path, header_change=None, pixel_change=None):
    """What an attacker (or a careless script) can do: edit, then recompute the unkeyed hash."""
    exr = OpenEXR.File(str(path), separate_channels=True)
    header = dict(exr.header())
    pixels = {name: c.pixels.copy() for name, c in exr.channels().items()}
    for key in ("channels", "dataWindow", "displayWindow"):
        header.pop(key, None)
    if header_change:
        header_change(header)
    if pixel_change:
        pixel_change(pixels)
    names = json.loads(header["bsdflab.channels"])
    order = [f"f.{n}" for n in names] + [f"err.{n}" for n in names] + ["samples"]
    header["bsdflab.content_hash"] = file_format.content_hash(
        {k: v for k, v in header.items() if k.startswith("bsdflab.")}, [pixels[n] for n in order])
    OpenEXR.File(header, pixels).write(str(path))


def _set(name, value):
    return lambda h: h.update({name: value})


def _scale(channel, factor):
    def change(p):
        p[channel][...] = p[channel] * factor
    return change


@pytest.mark.parametrize("header_change, pixel_change, match", [
    # negative values (one RGB channel alone may dip below 0: out-of-gamut spectra)
    (None, lambda p: [p[c].__setitem__(..., -p[c]) for c in ("f.R", "f.G")], "luminance"),
    (None, _scale("err.G", -1.0), "standard errors must be >= 0"),
    (None, lambda p: p["samples"].__setitem__(..., 0), ">= 1 sample"),
    (_set("bsdflab.rel_error_target", "NaN"), None, "NaN"),
    (_set("bsdflab.model", '{"type":"layered"}'), None, "model"),
    (_set("bsdflab.model", '{"type":"roughdielectric","alpha":0.1}'), None, "transmi"),
    (_set("bsdflab.grid", '{"n_phi":4,"n_theta_i":3,"n_theta_o":5,"thickness_nm":[1e308]}'), None, "thickness"),
    (_set("bsdflab.grid", '{"n_phi":4,"n_theta_i":3,"n_theta_o":5,"extra":1}'), None, "unknown table grid keys"),
])
def test_02_edited_and_rehashed_tables_are_refused(tmp_path, header_change, pixel_change, match):
    # old: all of these loaded (the hash matched), failing later or silently wrong
    path = tmp_path / "t.exr"
    write_table(path, _valid_table())
    _edit_and_rehash(path, header_change, pixel_change)
    with pytest.raises(ValueError, match=match):
        read_table(path)


def test_02_signed_tables_verify_and_edits_are_caught(tmp_path, monkeypatch):
    # old: no signatures; an edited, re-hashed file loaded
    path = tmp_path / "t.exr"
    key = "a secret of at least sixteen bytes"
    write_table(path, _valid_table(), key=key)
    assert read_table(path, key=key).model == MODEL
    with pytest.raises(ValueError, match="does not verify"):
        read_table(path, key="another secret of sixteen bytes")
    monkeypatch.setenv("BSDFLAB_TABLE_KEY", key)
    assert read_table(path).model == MODEL  # the key from the environment
    _edit_and_rehash(path, pixel_change=_scale("f.G", 2.0))
    with pytest.raises(ValueError, match="does not verify"):
        read_table(path)

    # a grid reshaped to the same cell count and image shape (theta_o <-> phi) passes every
    # check of meaning: only the signature tells
    write_table(path, _valid_table())  # signed with the environment's key
    _edit_and_rehash(path, _set("bsdflab.grid", '{"n_phi":5,"n_theta_i":3,"n_theta_o":4,"thickness_nm":[]}'))
    with pytest.raises(ValueError, match="does not verify"):
        read_table(path)
    monkeypatch.delenv("BSDFLAB_TABLE_KEY")
    assert read_table(path).grid.n_phi == 5  # without a key nothing can tell (documented)

    write_table(tmp_path / "plain.exr", _valid_table())
    with pytest.raises(ValueError, match="not signed"):
        read_table(tmp_path / "plain.exr", key=key)
    with pytest.raises(ValueError, match="at least 16 bytes"):
        read_table(tmp_path / "plain.exr", key="short")


# -- 3. indices, films, wavelengths ------------------------------------------------------------
@pytest.mark.parametrize("make, name", [
    (lambda: bl.Dielectric(int_ior=1e-200), "int_ior"),          # old: sampled NaN directions
    (lambda: bl.Dielectric(ext_ior=1e-320), "ext_ior"),          # old: infinite eta, NaN weight
    (lambda: bl.RoughDielectric(0.3, int_ior=1e200), "int_ior"),  # old: eval NaN
    (lambda: bl.Dielectric(int_ior=1e3, ext_ior=1.0), "int_ior / ext_ior"),
    (lambda: bl.Conductor(eta=1e-9, k=1.0), "eta"),
    (lambda: bl.Conductor(eta=1.0, k=1e9), "k"),
    (lambda: bl.Dielectric(film=[{"material": 1e39, "thickness_nm": 100}]), "material"),
    (lambda: bl.Dielectric(film=[{"material": 1.5, "thickness_nm": 1e308}]), "thickness_nm"),
])
def test_03_indices_outside_the_physical_range_are_refused(make, name):
    with pytest.raises(ValueError, match=name):
        make()


@pytest.mark.parametrize("call, name", [
    (lambda: optics.film_reflectance((1.0, 4e38, 100.0, 1.5), 550.0, 0.3), "n1"),       # old: NaN
    (lambda: optics.film_reflectance((1e-201, 1.5, 100.0, 1.5), 550.0, 0.3), "n0"),
    (lambda: optics.film_reflectance((1.0, 1.5, 1e308, 1.5), 550.0, 0.3), "d_nm"),
    (lambda: optics.film_reflectance((1.0, 1.5, 100.0, 1.5), 1e-310, 0.3), "wavelength_nm"),
    (lambda: optics.film_transmittance((1.0, 1.5, 100.0, 1.5), 550.0, 0.3, thickness_nm=1e308), "thickness_nm"),
    (lambda: optics.fresnel_reflectance(0.5, 1e-250, 1.5), "n_i"),
    (lambda: bl.Diffuse(0.5).eval(UP, OBLIQUE, wavelengths=[5e-324]), "wavelengths"),
    (lambda: bl.Dielectric(film=[{"material": 1.8, "thickness_nm": 300}]).sample(OBLIQUE, thickness=1e300), "thickness"),
])
def test_03_optics_refuse_what_would_be_nan(call, name):
    with pytest.raises(ValueError, match=name):
        call()


def test_03_accepted_extremes_stay_finite():
    # the ends of the documented ranges: every output finite
    for model in (bl.Dielectric(1e3, 1e3 / 100), bl.Dielectric(1e-3, 1e-3 * 100), bl.RoughDielectric(0.3, 2.0, 1e-3 * 100),
                  bl.RoughDielectric(4.0, 1e3, 10.0), bl.Conductor(eta=1e-3, k=1e3), bl.RoughConductor(1e-4, eta=1e3, k=0.0)):
        wi = np.array([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8], [0.999, 0.0, np.sqrt(1 - 0.999**2)]])
        s = model.sample(wi, seed=1)
        for a in (model.eval(wi, wi[::-1]), model.pdf(wi, wi[::-1]), s.weight, s.wo, s.pdf):
            assert np.all(np.isfinite(a)), model
    r = optics.film_reflectance((1e-3, 1e3, 1e9, 1e3 + 1e3j), [1.0, 1e12], cos_theta=[0.0, 1.0])
    assert np.all(np.isfinite(r)) and np.all((r >= 0) & (r <= 1))


def test_03_index_matched_and_absent_films_at_grazing_are_finite():
    # found by this issue's fuzzing (old: NaN): equal media, or a zero-thickness film
    # between equal media, near grazing incidence divided 0 by 0; either is no interface
    c = np.array([1e-30, 1e-70, 1e-300, 0.5])
    assert np.array_equal(optics.fresnel_reflectance(c, 1.5, 1.5).unpolarised, np.zeros(4))
    assert np.array_equal(optics.fresnel_transmittance(c, 1.5, 1.5).unpolarised, np.ones(4))
    for film in ((1.0, 2.0, 0.0, 1.0), (1.3, 1.3, 100.0, 1.3), (1.3, 1.3, 0.0, 1.3)):
        r = optics.film_reflectance(film, 500.0, cos_theta=c)
        t = optics.film_transmittance(film, 500.0, cos_theta=c)
        np.testing.assert_allclose(r, 0.0, atol=1e-12)
        np.testing.assert_allclose(t, 1.0, atol=1e-12)


def test_04_one_sample_render_says_its_variance_is_undefined():
    # old: variance was inf everywhere
    result = render(scene("furnace", width=4, height=3), spp=1, progress=False)
    assert not result.variance_defined and result.summary()["variance_defined"] is False
    assert np.all(np.isfinite(result.variance)) and np.all(result.variance == 0)
    two = render(scene("furnace", width=4, height=3), spp=2, progress=False)
    assert two.variance_defined and np.all(np.isfinite(two.variance))


# -- 5. errors of the wrong kind ---------------------------------------------------------------
HUGE = 10**400


@pytest.mark.parametrize("call", [
    lambda: bl.Diffuse(HUGE), lambda: bl.Dielectric(HUGE), lambda: bl.RoughDielectric(HUGE),
    lambda: bl.Conductor(eta=HUGE), lambda: bl.Slab(HUGE), lambda: bl.PhaseFunction("hg", g=HUGE),
    lambda: bl.Diffuse(0.5).eval([HUGE, 0, 1], UP), lambda: bl.Diffuse(0.5).eval(UP, UP, wavelengths=[HUGE]),
    lambda: bl.Diffuse(0.5).eval(UP, UP, lobes=HUGE), lambda: bl.Diffuse(0.5).eval(UP, UP, lobes=float("inf")),
    lambda: bl.Dielectric(film=[{"material": 1.5, "thickness_nm": 100}]).eval(UP, UP, thickness=HUGE),
    lambda: optics.film_reflectance((1.0, 1.5, HUGE, 1.5), 550.0, 0.3),
    lambda: optics.fresnel_reflectance(0.5, HUGE, 1.5),
    lambda: bl.Diffuse(0.5).sample(UP, seed=2**64),                       # old: pybind TypeError
    lambda: bl.Layered([bl.Dielectric()], [bl.Slab()], bl.Diffuse(), samples=2**31),  # old: accepted
    lambda: bl.Layered([bl.Dielectric()], [bl.Slab()], bl.Diffuse(), max_depth=2**40),
    lambda: bl.from_dict({"type": []}),                                   # old: TypeError
    lambda: bl.from_dict({"type": "diffuse", 3: 1}),
    lambda: bl.Conductor(material=["Au"]),
    lambda: bl.Diffuse(0.5, two_sided="no"),
    lambda: presets.iridophore_stack(float("nan")),                       # old: TypeError
    lambda: presets.iridophore_stack(-5),                                 # old: silently no film
    lambda: presets.iridophore_stack(10**7),                              # old: a 20-million list first
    lambda: presets.melanin_absorption({}),                               # old: TypeError
    lambda: presets.melanin_absorption(1.2, HUGE),
    lambda: presets.preset("xenopeltis", colour=1),
    lambda: TableBSDF(4.0),                                               # old: TypeError
    lambda: TableGrid(3, 5, 4, "abc"),
    lambda: TableGrid.from_dict([1, 2]),
])
def test_05_bad_input_is_a_value_error(call):
    with pytest.raises(ValueError) as info:
        call()
    assert "\n" not in str(info.value) and len(str(info.value)) < 400


def test_05_layered_samples_bound_is_the_core_s():
    walks = bl.Layered([bl.Dielectric()], [bl.Slab()], bl.Diffuse(), samples=1 << 24)  # the top is fine
    assert walks.samples == 1 << 24


# -- 6. the command line ------------------------------------------------------------------------
def _scene_file(tmp_path, shapes=None, depth=None):
    d = {"format": "bsdflab-scene", "version": 1,
         "camera": {"origin": [0, 0, 4], "target": [0, 0, 0], "width": 8, "height": 6},
         "shapes": shapes or [{"geometry": {"type": "sphere"}, "material": "m"}],
         "materials": {"m": {"bsdf": {"type": "diffuse"}}}, "environment": {"type": "constant"}}
    text = json.dumps(d)
    if depth:
        text = text[:-1] + ', "name": ' + "[" * depth + "]" * depth + "}"
    path = tmp_path / "scene.json"
    path.write_text(text)
    return path


def test_06_deeply_nested_scene_is_one_line(tmp_path):
    # old: RecursionError traceback
    one_line_error(cli("render", str(_scene_file(tmp_path, depth=200000)), "--out", str(tmp_path / "r.exr")),
                   "scene.json", "nested")


def test_06_ply_with_a_face_index_out_of_range_is_one_line(tmp_path):
    # old: IndexError traceback from trimesh
    ply = tmp_path / "bad.ply"
    ply.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                   "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
    path = _scene_file(tmp_path, shapes=[{"geometry": {"type": "mesh", "path": "bad.ply"}, "material": "m"}])
    one_line_error(cli("render", str(path), "--out", str(tmp_path / "r.exr"), "--quiet"), "bad.ply", "face indices")


@pytest.mark.parametrize("target", ["folder", "under_a_file"])
def test_06_unwritable_out_is_refused_before_work(tmp_path, target):
    # old: OSError traceback after the whole render
    (tmp_path / "folder.exr").mkdir()
    (tmp_path / "file").write_text("x")
    out = {"folder": tmp_path / "folder.exr", "under_a_file": tmp_path / "file" / "r.exr"}[target]
    result = cli("render", "furnace", "--width", "8", "--height", "8", "--spp", "4", "--quiet", "--out", str(out))
    one_line_error(result, "--out")
    # Checked before any work: even the scene name is not looked at yet (an unknown scene
    # would be the error otherwise), so no render can have run first.
    one_line_error(cli("render", "nosuch", "--quiet", "--out", str(out)), "--out")


def test_06_damaged_exr_attribute_names_the_file(tmp_path):
    # old: "'utf-8' codec can't decode byte ..." with no file name
    path = tmp_path / "t.exr"
    write_table(path, _valid_table())
    data = bytearray(path.read_bytes())
    at = data.index(b'"type":"diffuse"')
    data[at + 1] = 0xFF  # inside a string attribute: no longer UTF-8
    path.write_bytes(bytes(data))
    one_line_error(cli("table", "info", str(path)), str(path))
    with pytest.raises(ValueError, match="t.exr"):
        read_exr(path)


def test_06_sigint_is_one_line_and_exit_130(tmp_path):
    # old: a 30-line KeyboardInterrupt traceback, exit status 1
    proc = subprocess.Popen([*BSDFLAB, "render", "furnace", "--width", "256", "--height", "256", "--spp", "65536",
                             "--out", str(tmp_path / "r.exr")], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    seen = threading.Event()
    chunks = []

    def read():
        for chunk in iter(lambda: proc.stderr.read(1), b""):
            chunks.append(chunk)
            if b"rendering" in b"".join(chunks[-64:]):
                seen.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    assert seen.wait(120), b"".join(chunks)
    proc.send_signal(signal.SIGINT)
    rc = proc.wait(120)
    reader.join(10)
    err = b"".join(chunks).decode(errors="replace")
    tail = [line for line in err.replace("\r", "\n").splitlines() if line.strip() and "rendering" not in line]
    assert rc == 130 and tail == ["bsdflab render: interrupted"], (rc, err[-2000:])
    assert not (tmp_path / "r.exr").exists() and not (tmp_path / "r.png").exists()


# -- 7. files ---------------------------------------------------------------------------------
def test_07_exr_and_png_are_published_together(tmp_path, monkeypatch):
    # old: an interrupt during tone mapping / PNG writing left the EXR without its PNG
    from PIL import Image

    from bsdflab.cli.main import main

    def interrupted(self, *args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(Image.Image, "save", interrupted)
    out = tmp_path / "r.exr"
    try:
        rc = main(["render", "furnace", "--width", "4", "--height", "3", "--spp", "2", "--quiet", "--out", str(out)])
    except KeyboardInterrupt:
        rc = "KeyboardInterrupt escaped main()"
    assert rc == 130
    assert os.listdir(tmp_path) == []  # neither file, and no temporary left


def test_07_stale_temporaries_of_ours_are_removed(tmp_path):
    # old: a SIGKILLed write's ".xxxxxxxx.tmp.exr" stayed forever
    from bsdflab.util.files import _HOST, stale_temporaries

    old = time.time() - 7200
    legacy = tmp_path / ".abcd1234.tmp.exr"
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    orphan = tmp_path / f".bsdflab-{_HOST}-{dead.pid}-x1y2z3.tmp.exr"
    fresh_legacy = tmp_path / ".wxyz9876.tmp.png"          # recent: maybe a writer at work
    live = tmp_path / f".bsdflab-{_HOST}-{os.getppid()}-q.tmp.exr"  # its process runs
    foreign = tmp_path / ".notes.tmp"                       # not our naming
    for p in (legacy, orphan, fresh_legacy, live, foreign):
        p.write_bytes(b"half")
    os.utime(legacy, (old, old))
    os.utime(foreign, (old, old))
    assert sorted(map(os.path.basename, stale_temporaries(str(tmp_path)))) == sorted([legacy.name, orphan.name])
    write_atomically(tmp_path / "x.txt", lambda tmp: open(tmp, "w").close())
    assert sorted(os.listdir(tmp_path)) == sorted([fresh_legacy.name, live.name, foreign.name, "x.txt"])
