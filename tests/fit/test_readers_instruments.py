"""Instrument formats for bsdflab fit import: Ocean Optics .ProcSpec (zip + XML) and
OceanView/SpectraSuite text, Avantes .ttt text and AvaSoft 8 binary, JCAMP-DX. Each file is
hand-made here in the format's exact layout (docs/fit_data.md), read back to the values
written, and broken in the ways real files break (truncated zip, bad XML, a non-numeric
cell at a known line and column) to check the message names the file and the place."""
from __future__ import annotations

import ctypes
import io
import zipfile

import numpy as np
import pytest

from bsdflab.fit.readers import ImportSpec, import_files, reader_for

WL = np.array([399.8, 450.1, 500.3, 550.2, 600.0])
PCT = np.array([12.5, 18.0, 30.25, 22.0, 15.5])
SPEC = ImportSpec(geometry="specular", units="percent", sigma_absolute=0.5, angle_deg=20.0)


def procspec_xml(wl, processed, wl_tag="channelWavelengths"):
    doubles = lambda v: "".join(f"<double>{float(x)!r}</double>" for x in v)  # noqa: E731
    return ("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<com.oceanoptics.omnidriver.spectra.OmniSpectrum>\n"
            "  <saveTime><milliTime>1417000000000</milliTime></saveTime>\n"
            "  <userName>lab\u00e9</userName>\n"
            "  <sourceSpectra><com.oceanoptics.omnidriver.spectra.OmniSpectrum>\n"
            f"    <pixelValues>{doubles(processed * 40)}</pixelValues>\n"
            f"    <{wl_tag}>{doubles(wl)}</{wl_tag}>\n"
            "    <integrationTime>100000</integrationTime><scansToAverage>10</scansToAverage>\n"
            "    <spectrometerSerialNumber>USB2E7196</spectrometerSerialNumber>\n"
            "  </com.oceanoptics.omnidriver.spectra.OmniSpectrum></sourceSpectra>\n"
            f"  <darkSpectrum><pixelValues>{doubles(np.zeros(len(wl)))}</pixelValues></darkSpectrum>\n"
            f"  <referenceSpectrum><pixelValues>{doubles(np.full(len(wl), 4000.0))}</pixelValues></referenceSpectrum>\n"
            f"  <processedPixels>{doubles(processed)}</processedPixels>\n"
            "</com.oceanoptics.omnidriver.spectra.OmniSpectrum>\n")


def write_procspec(path, xml, member="ps_0.xml"):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr(member, xml.encode("latin-1") + b"\x01")   # SpectraSuite writes stray bytes
        z.writestr("OOISignatures.xml", "<signatures/>")
    return str(path)


def test_procspec(tmp_path):
    """The processed spectrum, not the raw sample counts beside it (pixelValues are 40x the
    processed values here: a reader taking the first <double> list would be caught), and the
    angle from the file name."""
    path = write_procspec(tmp_path / "scan_20deg.ProcSpec", procspec_xml(WL, PCT))
    assert reader_for(path).name == "procspec"
    ds, _ = import_files([path], ImportSpec(geometry="specular", units="percent", sigma_absolute=0.5))
    assert ds.angle_deg.tolist() == [20.0] * 5            # from the file name
    np.testing.assert_allclose(ds.wavelength_nm, WL, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.reflectance, PCT / 100, rtol=1e-9, atol=0)


@pytest.mark.parametrize("make, match", [
    (lambda p: p.write_bytes(zipfile_bytes(procspec_xml(WL, PCT))[:120]), r"not a readable ProcSpec \(zip\) archive"),
    (lambda p: write_procspec(p, procspec_xml(WL, PCT).replace("</processedPixels>", "</processed>")),
     r"ps_0\.xml: line 13, column \d+: bad XML: mismatched tag"),
    (lambda p: write_procspec(p, procspec_xml(WL, PCT).replace("<double>30.25</double>", "<double>n/a</double>")),
     r"ps_0\.xml: <processedPixels> value 3 is not a number: 'n/a'"),
    (lambda p: write_procspec(p, procspec_xml(WL, PCT, wl_tag="wavelengths")), r"no <channelWavelengths> element"),
    (lambda p: write_procspec(p, procspec_xml(WL, PCT), member="other.xml"), r"expected one ps_<n>\.xml document"),
    (lambda p: write_procspec(p, procspec_xml(WL[:4], PCT)), r"4 channelWavelengths but 5 processedPixels"),
])
def test_bad_procspec(tmp_path, make, match):
    path = tmp_path / "s.ProcSpec"
    make(path)
    with pytest.raises(ValueError, match=r"s\.ProcSpec.*" + match):
        import_files([str(path)], SPEC)


def procspec_chain_xml(wl, processed, last_ref="../../stage[2]/processedPixels"):
    """SpectraSuite's real layout (tests/fit/data/instruments/standard-blue.ProcSpec): one
    processedPixels per processing stage, written once and otherwise XStream references;
    the first stage's points at the raw counts."""
    doubles = lambda v: "".join(f"<double>{float(x)!r}</double>" for x in v)  # noqa: E731
    return ("<spectrum>\n"
            f"  <sourceSpectra><omni><pixelValues>{doubles(processed * 40)}</pixelValues>\n"
            f"    <channelWavelengths>{doubles(wl)}</channelWavelengths></omni></sourceSpectra>\n"
            "  <certificates>\n"
            "    <stage><processedPixels reference=\"../../../sourceSpectra/omni/pixelValues\"/></stage>\n"
            f"    <stage><processedPixels>{doubles(processed)}</processedPixels></stage>\n"
            f"    <stage><processedPixels reference=\"{last_ref}\"/></stage>\n"
            "  </certificates>\n"
            "</spectrum>\n")


@pytest.mark.parametrize("last_ref", ["../../stage[2]/processedPixels",
                                      "/spectrum/certificates/stage[2]/processedPixels",
                                      "../../stage[3]/../stage[2]/processedPixels"])
def test_procspec_references(tmp_path, last_ref):
    """The last stage's pixels, references followed (relative, absolute, through a
    sibling), not the raw counts the first stage points at (40x the values here)."""
    path = write_procspec(tmp_path / "scan_20deg.ProcSpec", procspec_chain_xml(WL, PCT, last_ref))
    ds, _ = import_files([path], SPEC)
    np.testing.assert_allclose(ds.reflectance, PCT / 100, rtol=1e-9, atol=0)


@pytest.mark.parametrize("last_ref, match", [
    ("../../stage[7]/processedPixels", r"the reference '\.\./\.\./stage\[7\]/processedPixels' names no element "
                                       r"at 'stage\[7\]'"),
    ("../../../../../x", r"the reference '(\.\./)+x' climbs above the document"),
    ("/other/certificates", r"the reference '/other/certificates' names no element at 'other'"),
    (".", r"more than 16 references in a chain \(a cycle\)"),
    ("a/../" * 40, r"a reference of 80 steps \(at most 64\)"),   # bounded: an upload may be hostile
])
def test_bad_procspec_reference(tmp_path, last_ref, match):
    path = tmp_path / "s.ProcSpec"
    write_procspec(path, procspec_chain_xml(WL, PCT, last_ref))
    with pytest.raises(ValueError, match=r"s\.ProcSpec: ps_0\.xml: <processedPixels>: " + match):
        import_files([str(path)], SPEC)


def zipfile_bytes(xml):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("ps_0.xml", xml)
    return buf.getvalue()


def oceanview(values, columns=None, decimal="."):
    head = ("Data from scan_20deg.txt Node\n\nDate: Mon Jun 16 16:44:13 CEST 2014\nUser: lab\n"
            "Spectrometer: FLMS01234\nTrigger mode: 0\nIntegration Time (sec): 1.000000E-1\nScans to average: 10\n"
            "Electric dark correction enabled: true\nNonlinearity correction enabled: false\nBoxcar width: 5\n"
            "XAxis mode: Wavelengths\nNumber of Pixels in Spectrum: 5\n>>>>>Begin Spectral Data<<<<<\n")
    rows = "".join((f"{w:.2f}\t{v:.3f}\n" if columns is None else f"{w:.2f}\t1.0\t2.0\t3.0\t{v:.3f}\n")
                   .replace(".", decimal) for w, v in zip(WL, values))
    return head + (columns + "\n" if columns else "") + rows + ">>>>>End Spectral Data<<<<<\n"


@pytest.mark.parametrize("columns, decimal", [(None, "."), (None, ","), ("W\tD\tR\tS\tP", ".")])
def test_oceanview_text(tmp_path, columns, decimal):
    path = tmp_path / "scan.txt"
    path.write_text(oceanview(PCT, columns, decimal), encoding="latin-1")
    assert reader_for(str(path)).name == "oceanview"
    ds, _ = import_files([str(path)], SPEC)
    np.testing.assert_allclose(ds.reflectance, PCT / 100, rtol=1e-9, atol=0)
    np.testing.assert_allclose(ds.wavelength_nm, np.round(WL, 2), rtol=0, atol=1e-9)


def test_bad_oceanview_text(tmp_path):
    path = tmp_path / "scan.txt"
    path.write_text(oceanview(PCT).replace("30.250", "30.2x"), encoding="utf-8")
    with pytest.raises(ValueError, match=r"scan\.txt: line 17, column 2: the value must be a number, got '30\.2x'"):
        import_files([str(path)], SPEC)
    path.write_text(oceanview(PCT), encoding="utf-8")
    with pytest.raises(ValueError, match=r"scan\.txt, line 17: the values look like percent"):
        import_files([str(path)], ImportSpec(geometry="specular", sigma_absolute=0.5, angle_deg=20.0))


def ttt(values, processed=True):
    head = ("1305084U1-feather 3\nIntegration time: 10.00 ms\nAverage: 5 scans\nNr of pixels used for smoothing: 2\n"
            "Data measured with spectrometer name: 1305084U1\n")
    if processed:
        cols = "Wave   ;Sample   ;Dark     ;Reference;Reflectance\n"
        units = "[nm]   ;[counts] ;[counts] ;[counts] ;[%]\n"
        rows = "".join(f"{w:7.2f};{4000 * v / 100 + 100:9.2f};{100.0:9.2f};{4100.0:9.2f};{v:7.3f}\n".replace(".", ",")
                       for w, v in zip(WL, values))
    else:
        cols, units = "Wave   ;Sample   ;Dark     ;Reference\n", "[nm]   ;[counts] ;[counts] ;[counts]\n"
        rows = "".join(f"{w:.2f};{4000 * v / 100 + 100:.4f};100.0;4100.0\n" for w, v in zip(WL, values))
    return head + cols + units + "\n" + rows


@pytest.mark.parametrize("processed", [True, False])
def test_avantes_ttt(tmp_path, processed):
    """The processed column in percent (its unit line says [%], so no units need declaring),
    or without it the ratio (Sample - Dark) / (Reference - Dark) as a fraction."""
    path = tmp_path / "feather_20deg.ttt"
    path.write_text(ttt(PCT, processed), encoding="latin-1")
    ds, _ = import_files([str(path)], ImportSpec(geometry="specular", sigma_relative=0.01))
    np.testing.assert_allclose(ds.reflectance, PCT / 100, rtol=1e-6, atol=0)
    with pytest.raises(ValueError, match="the file states its values are in"):
        import_files([str(path)], ImportSpec(geometry="specular", sigma_relative=0.01,
                                             units="fraction" if processed else "percent"))


def test_bad_avantes_ttt(tmp_path):
    """Lines counted from 1 in the file (the column line is line 6; a data row two below the
    unit line and a blank is line 11: an off-by-one in the count is caught)."""
    path = tmp_path / "f.ttt"
    path.write_text(ttt(PCT).replace("30,250", "30;250"), encoding="latin-1")
    with pytest.raises(ValueError, match=r"f\.ttt: line 11: expected 5 values as in the column line \(line 6\), got 6"):
        import_files([str(path)], SPEC)
    path.write_text(ttt(PCT).replace("30,250", "3O,250"), encoding="latin-1")
    with pytest.raises(ValueError, match=r"f\.ttt: line 11, column 5 \('Reflectance'\): the value must be a number"):
        import_files([str(path)], SPEC)
    path.write_text("just some text\n", encoding="latin-1")
    with pytest.raises(ValueError, match=r"f\.ttt: no column line starting with 'Wave'"):
        import_files([str(path)], SPEC)


def raw8(path, wl, scope, dark, ref, pixels=None):
    """An AvaSoft 8 file in the layout avaread reads: the 'AVS' preamble, one channel block
    header (avaread.AvaTypes.AVSInfoBlock), then wavelength, scope, dark, reference as float32."""
    from avaread.AvaTypes import AVSInfoBlock, AVSPreamble

    pre = AVSPreamble(b"AVS", b"84", 1)
    info = AVSInfoBlock()
    n = len(wl) if pixels is None else pixels
    info.Measurement.StartPixel, info.Measurement.StopPixel = 0, n - 1
    info.blockLength = ctypes.sizeof(info) + 16 * len(wl)
    data = np.concatenate([wl, scope, dark, ref]).astype(np.float32).tobytes()
    path.write_bytes(bytes(pre) + bytes(info) + data)
    return str(path)


def test_avantes_raw8(tmp_path):
    dark, ref = np.full(5, 100.0), np.full(5, 4100.0)
    scope = dark + (ref - dark) * PCT / 100
    path = raw8(tmp_path / "s_20deg.raw8", WL, scope, dark, ref)
    ds, _ = import_files([path], ImportSpec(geometry="specular", sigma_relative=0.01))
    np.testing.assert_allclose(ds.reflectance, PCT / 100, rtol=1e-6, atol=0)   # float32 storage
    np.testing.assert_allclose(ds.wavelength_nm, WL, rtol=1e-6, atol=0)
    (tmp_path / "old.trm").write_bytes(b"\x00\x01AvaSoft7 binary")
    with pytest.raises(ValueError, match=r"old\.trm: byte 1: not an AvaSoft 8 file.*export it as text"):
        import_files([str(tmp_path / "old.trm")], SPEC)
    short = raw8(tmp_path / "t.raw8", WL, scope, dark, ref, pixels=50)
    with pytest.raises(ValueError, match=r"t\.raw8: cannot read the AvaSoft 8 file|t\.raw8: the channel announces"):
        import_files([short], SPEC)


def jdx(values, yunits="REFLECTANCE", npoints=5):
    rows = "".join(f"{w:.1f}, {v}\n" for w, v in zip(WL, values))
    return (f"##TITLE=feather 20deg\n##JCAMP-DX=4.24\n##DATA TYPE=UV/VIS SPECTRUM\n##ORIGIN=lab\n##OWNER=public\n"
            f"##XUNITS=NANOMETERS\n##YUNITS={yunits}\n##XFACTOR=1\n##YFACTOR=1\n##FIRSTX={WL[0]:.1f}\n"
            f"##LASTX={WL[-1]:.1f}\n##NPOINTS={npoints}\n##XYPOINTS=(XY..XY)\n{rows}##END=\n")


def test_jcamp(tmp_path):
    path = tmp_path / "f_20deg.jdx"
    path.write_text(jdx(PCT / 100))
    ds, _ = import_files([str(path)], ImportSpec(geometry="specular", sigma_relative=0.01))
    np.testing.assert_allclose(ds.reflectance, PCT / 100, rtol=1e-9, atol=0)
    path.write_text(jdx(PCT, yunits="% REFLECTANCE"))
    ds, _ = import_files([str(path)], ImportSpec(geometry="specular", sigma_relative=0.01))
    np.testing.assert_allclose(ds.reflectance, PCT / 100, rtol=1e-9, atol=0)
    path.write_text(jdx(PCT / 100).replace("0.3025", "0.3o25"))
    with pytest.raises(ValueError, match=r"f_20deg\.jdx: lines 14-18: the data block gives 4 points but ##NPOINTS "
                                         r"says 5"):
        import_files([str(path)], SPEC)


def test_several_procspec_files_angles_from_the_sidecar(tmp_path):
    """One file per scan, angles and series from [files] entries (names without numbers in
    them), replicates averaged with SE = std(ddof=1)/sqrt(n) from numpy. Mutations caught: a
    population std (ddof=0), files keyed by path instead of name (the entries would not match)."""
    from bsdflab.fit.readers import parse_spec

    scans = {"a.ProcSpec": (25.0, PCT), "b.ProcSpec": (25.0, PCT * 1.1), "c.ProcSpec": (25.0, PCT * 0.95),
             "d.ProcSpec": (40.0, PCT * 0.8)}
    paths = [write_procspec(tmp_path / name, procspec_xml(WL, values)) for name, (_, values) in scans.items()]
    spec = parse_spec({"geometry": "specular", "units": "percent", "sigma": {"absolute": 0.2},
                       "files": {name: {"angle_deg": angle, "series": "bird"} for name, (angle, _) in scans.items()}},
                      "sidecar")
    ds, _ = import_files(paths, spec)
    reps = np.array([v for _, (a, v) in scans.items() if a == 25.0])
    at25 = ds.angle_deg == 25.0
    assert set(ds.series) == {"bird"} and at25.sum() == 5 and (ds.angle_deg == 40.0).sum() == 5
    np.testing.assert_allclose(ds.reflectance[at25], reps.mean(axis=0) / 100, rtol=1e-9, atol=0)
    se = reps.std(axis=0, ddof=1) / np.sqrt(3)
    np.testing.assert_allclose(ds.sigma[at25], np.hypot(se, 0.2) / 100, rtol=1e-5, atol=0)
    np.testing.assert_allclose(ds.sigma[~at25], 0.2 / 100, rtol=1e-5, atol=0)
