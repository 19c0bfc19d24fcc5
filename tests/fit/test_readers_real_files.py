"""Real third-party instrument files (tests/fit/data/instruments/, sources and licences in
SOURCES.md there) read by bsdflab's readers and checked against what the same bytes say
when read by an independent path written here: zipfile + ElementTree walking the XStream
document by hand (.ProcSpec), struct at the AvaSoft 8 header's offsets (.Raw8), the
JCAMP-DX text's own lines and header (.jdx), the rows between the markers (OOIBase32
text). Each file is also checked for its wavelength range, its units and what
`bsdflab fit import` makes of it."""
from __future__ import annotations

import re
import struct
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest

from bsdflab.fit.readers import ImportSpec, import_files, reader_for

DATA = Path(__file__).parent / "data" / "instruments"
OMNI = "com.oceanoptics.omnidriver.spectra.OmniSpectrum"


def _doubles(el) -> np.ndarray:
    return np.array([float(d.text) for d in el.iter("double")])


def _procspec_by_hand(path):
    """Wavelengths, processed pixels, and sample, dark and reference counts, found where
    this file keeps them: the source spectrum, and the ReflectionCoreProcessor stage of the
    processing chain (the one stage whose pixels are written out, not referenced)."""
    with zipfile.ZipFile(path) as z:
        root = ElementTree.fromstring(z.read("ps_55.xml").decode("ascii", errors="ignore"))
    src = root.find(f"sourceSpectra/{OMNI}")
    stages = list(root.find("certificates"))
    core = next(s for s in stages if s.findtext("clazz", "").endswith("ReflectionCoreProcessor"))
    return (src, stages, core, _doubles(src.find("channelWavelengths")), _doubles(core.find("processedPixels")),
            _doubles(src.find("pixelValues")), _doubles(core.find("darkSpectrum/pixelValues")),
            _doubles(core.find("referenceSpectrum/pixelValues")))


def test_procspec_usb4000_reflectance_scan():
    """SpectraSuite's own file: the reader returns the reflectance stage (percent), not the
    raw counts the first stage's reference points at; the values are 100 (S - D) / (R - D)
    of the counts stored beside them and the wavelengths are the stored calibration
    polynomial, 3648 pixels, 179.74-882.36 nm."""
    path = str(DATA / "standard-blue.ProcSpec")
    src, stages, core, wl, processed, sample, dark, ref = _procspec_by_hand(path)
    # the layout the reader has to cope with: 5 stages, the first pointing at the raw counts,
    # the last three at the core stage's pixels
    refs = [s.find("processedPixels").get("reference") for s in stages]
    assert refs[0] == f"../../../sourceSpectra/{OMNI}/pixelValues" and refs[1] is None
    assert all(r.endswith("ProcessedSpectrumCertificate[2]/processedPixels") for r in refs[2:])
    assert len(wl) == len(processed) == int(src.findtext("numberOfPixels")) == 3648
    assert src.findtext("spectrometerSerialNumber") == "USB4A00229"
    assert core.find("yUnits").get("class").endswith("ReflectionIntensityDescriptor")   # percent, 0-110

    assert reader_for(path).name == "procspec"
    curve = reader_for(path).read(path, None)[0]
    np.testing.assert_array_equal(curve.wavelength_nm, wl)
    np.testing.assert_array_equal(curve.value, processed)
    c = src.find("channelCoefficients")
    p = np.arange(len(wl))
    poly = sum(float(c.findtext(t)) * p**k for k, t in enumerate(("__WlIntercept", "__WlFirst", "__WlSecond",
                                                                   "__WlThird")))
    np.testing.assert_allclose(curve.wavelength_nm, poly, rtol=0, atol=1e-9)
    assert (curve.wavelength_nm[0], curve.wavelength_nm[-1]) == (179.7399, pytest.approx(882.36018783, abs=1e-8))
    above = wl > 350   # below, reference ~ dark and the ratio is noise
    np.testing.assert_allclose(curve.value[above], 100 * (sample - dark)[above] / (ref - dark)[above], rtol=1e-12)
    assert 10 < np.median(curve.value[above]) < 70            # percent, not counts (~1500-33000)

    ds, _ = import_files([path], ImportSpec(geometry="diffuse", units="percent", sigma_absolute=0.5,
                                            angle_deg=45.0, angle_out_deg=0.0))
    keep = (wl >= 350) & (wl <= 1000)
    assert len(ds.wavelength_nm) == keep.sum() == 2831
    np.testing.assert_allclose(ds.wavelength_nm, wl[keep], rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.reflectance, processed[keep] / 100, rtol=1e-9)
    assert ds.wavelength_nm.min() == pytest.approx(350.042046, abs=1e-6) and ds.wavelength_nm.max() == wl[-1]


def test_avasoft8_raw8_scope_dark_reference():
    """AvaSoft 8 binary: the four float32 arrays (wavelength, scope, dark, reference) start
    after the 328-byte header; startPixel/stopPixel are the uint16 at bytes 89 and 91. The
    reader's value is (scope - dark) / (reference - dark), a fraction, 1331 pixels,
    335.77-1100.21 nm."""
    path = str(DATA / "example.Raw8")
    raw = Path(path).read_bytes()
    assert raw[:5] == b"AVS84"
    start, stop = struct.unpack_from("<HH", raw, 89)
    n = stop - start + 1
    wl, scope, dark, ref = np.frombuffer(raw, "<f4", count=4 * n, offset=328).reshape(4, n).astype(float)
    assert n == 1331 and np.all(np.diff(wl) > 0)

    assert reader_for(path).name == "avantes-raw8"
    curve = reader_for(path).read(path, None)[0]
    assert curve.units == "fraction"
    np.testing.assert_array_equal(curve.wavelength_nm, wl)
    np.testing.assert_allclose(curve.value, (scope - dark) / (ref - dark), rtol=1e-12, atol=0)
    assert curve.wavelength_nm[0] == pytest.approx(335.76514, abs=1e-5)
    assert curve.wavelength_nm[-1] == pytest.approx(1100.2117, abs=1e-4)

    ds, _ = import_files([path], ImportSpec(geometry="diffuse", sigma_relative=0.02, angle_deg=0.0,
                                            angle_out_deg=45.0))
    keep = (wl >= 350) & (wl <= 1000)
    assert len(ds.wavelength_nm) == keep.sum() == 1124
    np.testing.assert_allclose(ds.reflectance, ((scope - dark) / (ref - dark))[keep], rtol=1e-9)


def _jcamp_by_hand(path):
    """Header values and the ##XYDATA=(X++(Y..Y)) block: each line is an abscissa then
    '+'-separated integer ordinates, scaled by ##YFACTOR; abscissas are FIRSTX + k DELTAX."""
    lines = Path(path).read_text(encoding="latin-1").splitlines()
    head = dict(ln[2:].split("=", 1) for ln in lines if ln.startswith("##") and "=" in ln)
    first = lines.index("##XYDATA=(X++(Y..Y))") + 1
    block = lines[first:lines.index("##END=")]
    ints = [int(v) for ln in block for v in re.split(r"[+]", ln)[1:]]
    y = np.array(ints) * float(head["YFACTOR"])
    x = float(head["FIRSTX"]) + np.arange(len(y)) * float(head["DELTAX"])
    return head, x, y


def test_jcamp_hemispherical_reflectance_in_wavenumbers():
    """A JCAMP-DX FTIR reflectance spectrum in 1/cm: the reader turns wavenumbers into nm
    (1e7 / x), sorts them ascending and keeps the scaled ordinates, 7154 points
    (##NPOINTS), 1333.5-16669 nm, FIRSTY and MAXY as the header states; no unit stated
    (##YUNITS=Reflectance names no percent). All of it lies outside 350-1000 nm: the import
    refuses it, naming the range."""
    path = str(DATA / "fitr_nitrocellulose.jdx")
    head, x, y = _jcamp_by_hand(path)
    assert len(y) == int(head["NPOINTS"]) == 7154 and head["XUNITS"] == "1/cm"
    assert y[0] == pytest.approx(float(head["FIRSTY"]), rel=1e-8)
    assert y.max() == pytest.approx(float(head["MAXY"]), rel=1e-7)

    assert reader_for(path).name == "jcamp"
    curve = reader_for(path).read(path, None)[0]
    assert curve.units is None
    order = np.argsort(1e7 / x)
    np.testing.assert_allclose(curve.value, y[order], rtol=1e-12, atol=0)
    # the file writes abscissas to 0.01 cm-1; within that of FIRSTX + k DELTAX
    np.testing.assert_allclose(1e7 / curve.wavelength_nm, x[order], rtol=0, atol=1e-3)
    assert np.all(np.diff(curve.wavelength_nm) > 0)
    assert curve.wavelength_nm[0] == pytest.approx(1e7 / 7498.994, rel=1e-6)      # 1333.5 nm
    assert curve.wavelength_nm[-1] == pytest.approx(1e7 / float(head["LASTX"]), rel=1e-6)  # 16669 nm

    with pytest.raises(ValueError, match=r"fitr_nitrocellulose\.jdx: ##XYDATA: no wavelength inside the "
                                         r"model's range 350-1000 nm"):
        import_files([path], ImportSpec(geometry="total", sigma_relative=0.02, angle_deg=8.0))


def test_ooibase32_scope_text():
    """Ocean Optics OOIBase32 text (the family of OceanView/SpectraSuite text; CRLF line ends,
    suffix .scope, so the format is named): the rows between the markers, 2048 pixels,
    339.95-1013.55 nm, with their line numbers. The values are counts (a laser line, 656.6
    at 787.02 nm): undeclared, the units rule refuses them, naming that line."""
    path = str(DATA / "tsunami.scope")
    lines = Path(path).read_bytes().decode("ascii").split("\r\n")
    assert lines[0] == "OOIBase32 Version 1.0.1.6 Data File" and "Spectrometer Serial Number: USB2E2859" in lines
    begin, end = lines.index(">>>>>Begin Spectral Data<<<<<"), lines.index(">>>>>End Spectral Data<<<<<")
    rows = np.array([[float(c) for c in ln.split("\t")] for ln in lines[begin + 1:end]])
    assert rows.shape == (2048, 2) and (rows[0, 0], rows[-1, 0]) == (339.95, 1013.55)

    curve = reader_for(path, "oceanview").read(path, None)[0]
    assert curve.units is None
    np.testing.assert_array_equal(curve.wavelength_nm, rows[:, 0])
    np.testing.assert_array_equal(curve.value, rows[:, 1])
    np.testing.assert_array_equal(curve.lines, np.arange(begin + 2, end + 1))    # 1-based: 15 ... 2062

    inside = (rows[:, 0] >= 350) & (rows[:, 0] <= 1000)
    peak = int(np.flatnonzero(inside)[np.argmax(rows[inside, 1])])
    assert (rows[peak, 0], rows[peak, 1], begin + 2 + peak) == (787.02, 656.6, 1296)
    with pytest.raises(ValueError, match=r"tsunami\.scope, line 1296: the values look like percent \(a specular "
                                         r"reflectance of 656\.6"):
        import_files([path], ImportSpec(format="oceanview", geometry="specular", sigma_absolute=1.0, angle_deg=10.0))
    with pytest.raises(ValueError, match=r"cannot tell the format from the suffix '\.scope'"):
        reader_for(path)
