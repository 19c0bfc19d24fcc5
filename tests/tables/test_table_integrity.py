"""Table files are checked for meaning on load, and signed files for their signature: an
edited file whose unkeyed content hash was recomputed is refused (it loaded before)."""
from __future__ import annotations

import json

import OpenEXR
import pytest

from bsdflab.tables import file_format, read_table, write_table
from support.tables import MODEL, valid_table


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
def test_edited_and_rehashed_tables_are_refused(tmp_path, header_change, pixel_change, match):
    # old: all of these loaded (the hash matched), failing later or silently wrong
    path = tmp_path / "t.exr"
    write_table(path, valid_table())
    _edit_and_rehash(path, header_change, pixel_change)
    with pytest.raises(ValueError, match=match):
        read_table(path)


def test_signed_tables_verify_and_edits_are_caught(tmp_path, monkeypatch):
    # old: no signatures; an edited, re-hashed file loaded
    path = tmp_path / "t.exr"
    key = "a secret of at least sixteen bytes"
    write_table(path, valid_table(), key=key)
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
    write_table(path, valid_table())  # signed with the environment's key
    _edit_and_rehash(path, _set("bsdflab.grid", '{"n_phi":5,"n_theta_i":3,"n_theta_o":4,"thickness_nm":[]}'))
    with pytest.raises(ValueError, match="does not verify"):
        read_table(path)
    monkeypatch.delenv("BSDFLAB_TABLE_KEY")
    assert read_table(path).grid.n_phi == 5  # without a key nothing can tell (documented)

    write_table(tmp_path / "plain.exr", valid_table())
    with pytest.raises(ValueError, match="not signed"):
        read_table(tmp_path / "plain.exr", key=key)
    with pytest.raises(ValueError, match="at least 16 bytes"):
        read_table(tmp_path / "plain.exr", key="short")

