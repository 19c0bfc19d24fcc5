"""Table files (OpenEXR), the table cache and `bsdflab table`, on small synthetic tables."""
from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import OpenEXR
import platformdirs
import pytest

from bsdflab.tables import (
    TableData,
    TableGrid,
    cache_dir,
    cache_key,
    cached_table,
    file_format,
    read_attributes,
    read_table,
    write_table,
)

BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


# A valid model for each lobe count: layered (split) tables reflect only; the transmissive
# table is of a rough dielectric (loading rebuilds the model and checks it fits the table).
LAYERED = {"type": "layered", "interfaces": [{"type": "roughdielectric", "alpha": 0.08}],
           "slabs": [{"thickness_um": 4.0}], "base": {"type": "diffuse"}}
ROUGH = {"type": "roughdielectric", "alpha": 0.08}


def make_table(n_lobes=2, spectral=False, thickness=(), seed=0, model=None) -> TableData:
    rng = np.random.default_rng(seed)
    grid = TableGrid(3, 5, 4, tuple(thickness))
    lobes = ("reflection", "transmission")[:n_lobes]
    channels = ("412.5", "550", "700") if spectral else ("R", "G", "B")
    shape = (n_lobes, max(1, len(thickness)), 3, 5, 4, len(channels))
    values = rng.random(shape, dtype=np.float32) * 3
    values.flat[:4] = [-0.0, np.finfo(np.float32).max, np.float32(1e-45), 0.0]  # bit patterns to keep
    model = model if model is not None else (LAYERED if n_lobes == 1 else ROUGH)
    return TableData(
        model=model, grid=grid, lobes=lobes, channels=channels, split_direct=model["type"] == "layered",
        values=values, stderr=rng.random(shape, dtype=np.float32) * 0.02,
        samples=rng.integers(1, 2**31 - 1, shape[:-1]).astype(np.int32),
        rel_error_target=0.01, meta={"preset": "xenopeltis", "seconds": 1.25, "seed": 7})


@pytest.fixture
def table_file(tmp_path):
    path = tmp_path / "table.exr"
    write_table(path, make_table())
    return path


# -- round trip -----------------------------------------------------------------------------

@pytest.mark.parametrize("n_lobes", [1, 2])
@pytest.mark.parametrize("spectral", [False, True])
@pytest.mark.parametrize("thickness", [(), (300.0, 400.0, 650.5)])
def test_round_trip_is_bit_exact(tmp_path, n_lobes, spectral, thickness):
    table = make_table(n_lobes, spectral, thickness)
    write_table(tmp_path / "t.exr", table)
    back = read_table(tmp_path / "t.exr")
    for name in ("values", "stderr", "samples"):
        a, b = getattr(table, name), getattr(back, name)
        assert b.dtype == a.dtype and b.shape == a.shape
        assert a.tobytes() == b.tobytes(), name  # bit-exact, -0.0 and subnormals included
    for name in ("model", "grid", "lobes", "channels", "split_direct", "rel_error_target", "meta"):
        assert getattr(back, name) == getattr(table, name), name
    assert os.listdir(tmp_path) == ["t.exr"]  # no temporary file left


def test_flattening_layout_is_the_documented_one(table_file):
    table = read_table(table_file)
    exr = OpenEXR.File(str(table_file), separate_channels=True)
    image = exr.channels()["f.G"].pixels
    n_t, n_ti, n_phi = table.n_thickness, table.grid.n_theta_i, table.grid.n_phi
    lobe, t, ti, to, phi = 1, 0, 2, 3, 1
    assert image[(lobe * n_t + t) * n_ti + ti, to * n_phi + phi] == table.values[lobe, t, ti, to, phi, 1]
    assert exr.channels()["samples"].pixels.dtype == np.uint32


def test_attributes_are_strings_with_the_metadata(table_file):
    attributes = read_attributes(table_file)
    assert set(file_format.REQUIRED) <= set(attributes)
    assert all(isinstance(v, str) for v in attributes.values())
    assert attributes["bsdflab.colour_space"] == "linear sRGB (D65)"
    assert attributes["bsdflab.format_version"] == "3"
    assert len(attributes["bsdflab.content_hash"]) == 64


# -- damaged and foreign files ----------------------------------------------------------------

def test_truncated_file_is_a_clear_error(table_file, capfd):
    data = table_file.read_bytes()
    for cut in (len(data) // 2, 8, len(data) - 1, 3 * len(data) // 4):
        table_file.write_bytes(data[:cut])
        with pytest.raises(ValueError, match="corrupt|not a bsdflab table"):
            read_table(table_file)
    out, err = capfd.readouterr()
    assert out == "" and err == ""  # the library's diagnostics went into the message


def _rewrite(path, change_pixels=None, change_header=None):
    """Rewrite a table file keeping its (old) content hash attribute."""
    exr = OpenEXR.File(str(path), separate_channels=True)
    header = dict(exr.header())
    channels = {name: c.pixels.copy() for name, c in exr.channels().items()}
    for key in ("channels", "dataWindow", "displayWindow"):
        header.pop(key, None)
    (change_pixels or (lambda c: None))(channels)
    (change_header or (lambda h: None))(header)
    OpenEXR.File(header, channels).write(str(path))


def test_changed_value_fails_the_hash(table_file):
    def bump(channels):
        channels["f.G"][1, 2] = np.nextafter(channels["f.G"][1, 2], np.float32(10))

    _rewrite(table_file, change_pixels=bump)
    with pytest.raises(ValueError, match="corrupt: content hash mismatch"):
        read_table(table_file)


def test_changed_metadata_fails_the_hash(table_file):
    _rewrite(table_file, change_header=lambda h: h.update({"bsdflab.rel_error_target": "0.5"}))
    with pytest.raises(ValueError, match="content hash mismatch"):
        read_table(table_file)


def test_newer_format_version_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(file_format, "FORMAT_VERSION", 4)
    write_table(tmp_path / "v4.exr", make_table())
    monkeypatch.undo()
    with pytest.raises(ValueError, match="written by format version 4, this bsdflab reads versions 1, 2, 3"):
        read_table(tmp_path / "v4.exr")


def test_foreign_files_are_refused(tmp_path):
    text = tmp_path / "notes.exr"
    text.write_text("not an image\n")
    with pytest.raises(ValueError, match="not a bsdflab table \\(not an OpenEXR file\\)"):
        read_table(text)
    image = tmp_path / "photo.exr"
    OpenEXR.File({}, {"R": np.zeros((4, 4), np.float32)}).write(str(image))
    with pytest.raises(ValueError, match="not a bsdflab table \\(missing attribute bsdflab.format_version"):
        read_table(image)
    with pytest.raises(ValueError, match="does not exist"):
        read_table(tmp_path / "missing.exr")


def test_bad_tables_are_not_written(tmp_path):
    table = make_table()
    table.samples[0, 0, 0, 0, 0] = -1
    with pytest.raises(ValueError, match=">= 1 sample"):
        write_table(tmp_path / "t.exr", table)
    table = make_table()
    table.values = table.values[..., :2]
    with pytest.raises(ValueError, match="shape"):
        write_table(tmp_path / "t.exr", table)
    assert os.listdir(tmp_path) == []


def test_interrupted_write_leaves_nothing_behind(tmp_path, monkeypatch):
    target = tmp_path / "t.exr"
    write_table(target, make_table(seed=1))
    before = target.read_bytes()

    class FailingFile:
        def __init__(self, header, channels):
            pass

        def write(self, path):
            with open(path, "wb") as f:
                f.write(b"\x76\x2f\x31\x01 half an image")
            raise KeyboardInterrupt  # e.g. Ctrl-C in the middle of the write

    monkeypatch.setattr(OpenEXR, "File", FailingFile)
    with pytest.raises(KeyboardInterrupt):
        write_table(target, make_table(seed=2))
    with pytest.raises(KeyboardInterrupt):
        write_table(tmp_path / "new.exr", make_table(seed=2))
    assert os.listdir(tmp_path) == ["t.exr"]
    assert target.read_bytes() == before  # the old file is intact


# -- cache -----------------------------------------------------------------------------------

class Maker:
    def __init__(self):
        self.calls = 0

    def __call__(self):
        self.calls += 1
        return make_table(n_lobes=1, seed=self.calls, model=REQUEST[0])


REQUEST = ({"type": "diffuse", "reflectance": 0.5}, TableGrid(3, 5, 4), 0.01, ("R", "G", "B"))


def test_second_request_is_a_file_read(tmp_path):
    make = Maker()
    first, path, hit = cached_table(*REQUEST, make, directory=tmp_path)
    assert (hit, make.calls, path.parent) == (False, 1, tmp_path)
    second, path2, hit2 = cached_table(*REQUEST, make, directory=tmp_path)
    assert (hit2, make.calls, path2) == (True, 1, path)
    assert np.array_equal(first.values, second.values)


def test_corrupt_cache_file_is_rebuilt(tmp_path, caplog):
    make = Maker()
    _, path, _ = cached_table(*REQUEST, make, directory=tmp_path)
    path.write_bytes(path.read_bytes()[:100])
    with caplog.at_level(logging.WARNING, logger="bsdflab.tables.cache"):
        table, path2, hit = cached_table(*REQUEST, make, directory=tmp_path)
    assert (hit, make.calls, path2) == (False, 2, path)
    assert "rebuilding" in caplog.text
    assert np.array_equal(read_table(path).values, table.values)


def test_cache_dir_env_and_argument(tmp_path, monkeypatch):
    monkeypatch.setenv("BSDFLAB_CACHE_DIR", str(tmp_path / "env"))
    assert cache_dir() == tmp_path / "env"
    assert cache_dir(tmp_path / "arg") == tmp_path / "arg"
    _, path, _ = cached_table(*REQUEST, Maker())
    assert path.parent == tmp_path / "env"
    monkeypatch.delenv("BSDFLAB_CACHE_DIR")
    assert cache_dir() == Path(platformdirs.user_cache_dir("bsdflab")) / "tables"


def test_cache_key_is_canonical():
    model, grid, rel, channels = REQUEST
    key = cache_key(model, grid, rel, channels)
    assert key == cache_key(dict(reversed(list(model.items()))), grid.to_dict(), rel, list(channels))
    assert key != cache_key(model, grid, 0.02, channels)
    assert key != cache_key(model, TableGrid(3, 5, 5), rel, channels)
    assert key != cache_key(model, grid, rel, ("550",))


# -- the command line ------------------------------------------------------------------------

def cli(*args):
    return subprocess.run([*BSDFLAB, *args], capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("args", [["table", "--help"], ["table", "info", "--help"],
                                  ["table", "plot", "--help"]])
def test_table_help(args):
    r = cli(*args)
    assert r.returncode == 0 and "usage:" in r.stdout


def test_table_info_and_plot(tmp_path):
    path = tmp_path / "t.exr"
    write_table(path, make_table(2, spectral=True, thickness=(300.0, 400.0)))
    r = cli("table", "info", str(path))
    assert r.returncode == 0, r.stderr
    for text in ("roughdielectric (preset xenopeltis)", "reflection, transmission", "300, 400 nm",
                 "3 wavelengths", "spectral, nm", "median", "95th pct", "content hash  OK",
                 "format version 3", "from above only"):
        assert text in r.stdout, text
    out = tmp_path / "figs" / "t.png"
    r = cli("table", "plot", str(path), "--out", str(out), "--thickness-index", "1")
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == PNG_MAGIC
    assert os.listdir(out.parent) == ["t.png"]


def test_table_bad_file_is_a_message(tmp_path):
    bad = tmp_path / "bad.exr"
    write_table(bad, make_table())
    bad.write_bytes(bad.read_bytes()[: bad.stat().st_size // 2])
    for action in (["info", str(bad)], ["plot", str(bad), "--out", str(tmp_path / "x.png")]):
        r = cli("table", *action)
        assert r.returncode == 2
        assert "bsdflab table: error:" in r.stderr and "corrupt" in r.stderr
        assert "Traceback" not in r.stderr and r.stdout == ""
    assert not (tmp_path / "x.png").exists()
