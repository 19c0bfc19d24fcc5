"""bsdflab fit import: the wide CSV/TSV reader, the sidecar, the units rule, replicates, the
long CSV through the import, and the CLI. Files are hand-made in the exact layouts of
docs/fit_data.md. Every comparison is deterministic: values go through the CSV writer (10
significant digits, sigma 6), hence rtol 1e-9 on values and 1e-5 on sigma."""
from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from bsdflab.fit import read_csv
from bsdflab.fit.readers import READERS, ImportSpec, import_files, load_spec, parse_spec

WIDE = """# goniometer run 3
wavelength_nm,R_15deg,R_30deg_a,R_30deg_b,R_30deg_c
400,25.3,20.1,20.7,19.6
450,26.0,21.5,21.1,22.0
500,27.5,23.0,22.2,22.9
"""


def write(path, text):
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_registry_lists_every_format():
    assert set(READERS.names()) == {"long", "wide", "procspec", "oceanview", "avantes-ttt", "avantes-raw8", "jcamp"}


def test_wide_percent_with_replicates_and_reference(tmp_path):
    """Replicates averaged, sigma = sqrt(SE^2 + absolute^2) with SE = std(ddof=1)/sqrt(n) from
    numpy, percent converted, values times the standard's reflectance. Mutations caught:
    ddof=0 in the SE (sigma off by sqrt(3/2)), percent not converted (values x100), the
    reference not applied (values / 0.98), replicates not grouped (3 curves at 30°)."""
    data = write(tmp_path / "angles.csv", WIDE)
    write(tmp_path / "angles.csv.toml", 'geometry = "specular"\nunits = "percent"\n'
                                        '[reference]\nreflectance = 0.98\n[sigma]\nabsolute = 0.1\n')
    ds, notes = import_files([data], load_spec(tmp_path / "angles.csv.toml"))
    raw = np.array([[20.1, 20.7, 19.6], [21.5, 21.1, 22.0], [23.0, 22.2, 22.9]])
    se = raw.std(axis=1, ddof=1) / np.sqrt(3)
    at30 = ds.angle_deg == 30
    assert at30.sum() == 3 and (ds.angle_deg == 15).sum() == 3
    np.testing.assert_allclose(ds.wavelength_nm[at30], [400, 450, 500], rtol=0)
    np.testing.assert_allclose(ds.reflectance[at30], raw.mean(axis=1) / 100 * 0.98, rtol=1e-9, atol=0)
    np.testing.assert_allclose(ds.sigma[at30], np.hypot(se, 0.1) / 100 * 0.98, rtol=1e-5, atol=0)
    np.testing.assert_allclose(ds.sigma[~at30], 0.1 / 100 * 0.98, rtol=1e-5, atol=0)
    assert "averaged replicates: 1-3 per curve" in notes


def test_round_trip_through_the_written_file(tmp_path):
    data = write(tmp_path / "a.tsv", "wavelength\t15\ttheta=40\n400\t0.2\t0.3\n410\t0.25\t0.35\n")
    spec = ImportSpec(geometry="specular", sigma_absolute=0.01)
    ds, _ = import_files([data], spec)
    out = tmp_path / "d.csv"
    ds.write_csv(out)
    back = read_csv(out)
    for f in ("geometry", "angle_deg", "wavelength_nm", "reflectance", "sigma"):
        np.testing.assert_array_equal(getattr(back, f), getattr(ds, f))
    assert sorted(set(back.angle_deg)) == [15.0, 40.0]


@pytest.mark.parametrize("header", ["15", "15deg", "R_15deg", "theta=15", "R 15°", "aoi:15", "15deg_rep2"])
def test_header_names_carry_the_angle(tmp_path, header):
    data = write(tmp_path / "w.csv", f"wavelength_nm,{header}\n500,0.3\n")
    ds, _ = import_files([data], ImportSpec(geometry="specular", sigma_relative=0.02))
    assert ds.angle_deg.tolist() == [15.0]


def test_sidecar_columns_series_and_diffuse(tmp_path):
    data = write(tmp_path / "w.csv", "nm;bird1;bird2;skip\n500;0,30;0,40;9\n600;0,31;0,41;9\n")
    sidecar = write(tmp_path / "s.toml", """
decimal = ","
geometry = "diffuse"
angle_out_deg = 45
[sigma]
relative = 0.05
[columns.bird1]
angle_deg = 0
series = "bird 1"
[columns.bird2]
angle_deg = 10
series = "bird 2"
[columns.skip]
ignore = true
""")
    ds, _ = import_files([data], load_spec(sidecar))
    assert ds.series_names() == ["bird 1", "bird 2"]
    assert np.all(ds.angle_out_deg == 45) and ds.angle_deg.tolist() == [0, 0, 10, 10]
    np.testing.assert_allclose(ds.reflectance, [0.30, 0.31, 0.40, 0.41], rtol=1e-9, atol=0)


def test_resampling_onto_a_grid(tmp_path):
    """np.interp is the reference; a mutation to nearest-neighbour picks 0.2/0.4 instead."""
    data = write(tmp_path / "w.csv", "wl,20deg\n400,0.2\n420,0.4\n440,0.6\n")
    ds, _ = import_files([data], ImportSpec(geometry="total", sigma_absolute=0.01,
                                            wavelengths=np.array([405.0, 415.0, 430.0])))
    np.testing.assert_allclose(ds.reflectance, np.interp([405, 415, 430], [400, 420, 440], [0.2, 0.4, 0.6]),
                               rtol=1e-9, atol=0)


@pytest.mark.parametrize("text, sidecar, match", [
    ("wavelength_nm,R_15deg\n400,25.3\n", 'geometry = "specular"\n[sigma]\nabsolute = 0.5',
     r"w\.csv: column 2 'R_15deg', line 2: the values look like percent \(a specular reflectance of 25\.3.*"
     r"units = \"percent\""),
    ("wavelength_nm,R_15deg\n400,0.2\n450,abc\n", 'geometry = "specular"',
     r"w\.csv: line 3, column 2 \('R_15deg'\): the value must be a number, got 'abc'"),
    ("wavelength_nm,sample1\n400,0.2\n", 'geometry = "specular"\n[sigma]\nabsolute = 0.01',
     r"column 2 'sample1': no angle of incidence"),
    ("wavelength_nm,R_15deg\n400,0.2\n", '[sigma]\nabsolute = 0.01', r"no geometry: declare geometry"),
    ("wavelength_nm,R_15deg\n400,0.2\n", 'geometry = "specular"',
     r"sigma is 0 for specular 15° at 400 nm \(one curve only\)"),
    ("wavelength_nm,R_15deg,R_15deg\n400,0.2,0.3\n", 'geometry = "specular"', r"line 1, column 3: column 'R_15deg' "
                                                                                 r"is named twice"),
    ("wavelength_nm,R_15deg\n400,0.2,0.1\n", 'geometry = "specular"', r"w\.csv: line 2: expected 2 cells"),
    ("400,0.2\n410,0.3\n", 'geometry = "specular"', r"line 1: expected a header row"),
    ("wavelength_nm,R_15deg\n400,0.2\n", 'geometry = "specular"\ncolour = 1', r"unknown key\(s\) colour"),
    ("wavelength_nm,R_15deg\n400,0.2\n", 'geometry = "specular"\n[columns.R_16deg]\nangle_deg = 16',
     r"names a column that none of the files has"),
    ("wavelength_nm,R_15deg_30deg\n400,0.2\n", 'geometry = "specular"', r"holds several angles"),
    ("wavelength_nm,R_15deg\n400,0.2\n410,0.3\n405,0.3\n", 'geometry = "specular"\n[sigma]\nabsolute = 0.01',
     r"line 4: the wavelengths must increase \(410 then 405 nm\)"),
    ("wavelength_nm,R_15deg\n400,0.2\n", 'geometry = "mirror"', r"unknown geometry 'mirror'"),
    ("wavelength_nm,R_15deg\n400,0.2\n", 'geometry = "specular"\nunits = "permille"', r"units must be"),
    ("wavelength_nm,R_15deg\n400,0.2\n", 'geometry = "specular\n', r"not valid TOML"),
])
def test_bad_wide_files(tmp_path, text, sidecar, match):
    data = write(tmp_path / "w.csv", text)
    side = write(tmp_path / "w.csv.toml", sidecar)
    with pytest.raises(ValueError, match=match):
        import_files([data], load_spec(side))


def test_percent_declared_is_converted_and_fraction_declared_accepted(tmp_path):
    data = write(tmp_path / "w.csv", "wavelength_nm,R_15deg\n400,25.3\n")
    pct, _ = import_files([data], ImportSpec(geometry="specular", units="percent", sigma_absolute=0.5))
    np.testing.assert_allclose(pct.reflectance, [0.253], rtol=1e-9, atol=0)
    np.testing.assert_allclose(pct.sigma, [0.005], rtol=1e-5, atol=0)
    # declared fractions above 1 (a specular beam against a diffuse standard) are kept, and the
    # written file declares them so that reading it back does not refuse them
    frac, _ = import_files([data], ImportSpec(geometry="specular", units="fraction", sigma_absolute=0.5))
    out = tmp_path / "d.csv"
    frac.write_csv(out)
    assert "# units: fraction" in out.read_text()
    np.testing.assert_allclose(read_csv(out).reflectance, [25.3], rtol=1e-9, atol=0)


def test_long_csv_units_rule(tmp_path):
    """The long CSV refuses a specular 25.3 (the issue's case) unless declared; '# units:
    percent' converts. Mutation caught: a check on diffuse rows only lets 25.3 through."""
    rows = "angle_deg,wavelength_nm,reflectance,sigma,geometry\n10,500,25.3,0.5,specular\n"
    bad = write(tmp_path / "bad.csv", rows)
    with pytest.raises(ValueError, match=r"bad\.csv: line 2: column reflectance: the values look like percent.*"
                                         r"# units: percent"):
        read_csv(bad)
    good = write(tmp_path / "good.csv", "# units: percent\n" + rows)
    ds = read_csv(good)
    np.testing.assert_allclose([ds.reflectance[0], ds.sigma[0]], [0.253, 0.005], rtol=1e-12, atol=0)
    assert ds.comments == []
    # through the import: --units percent converts, the file is otherwise kept
    imported, _ = import_files([bad], ImportSpec(units="percent"))
    np.testing.assert_allclose(imported.reflectance, [0.253], rtol=1e-12, atol=0)
    with pytest.raises(ValueError, match="do not apply to the long CSV"):
        import_files([bad], ImportSpec(units="percent", geometry="specular"))
    with pytest.raises(ValueError, match="wavelengths do not apply to the long CSV"):
        import_files([bad], ImportSpec(units="percent", wavelengths=np.array([400.0, 500.0])))
    imported, _ = import_files([bad], ImportSpec(units="percent", series="run"))
    assert imported.series.tolist() == ["run"]
    with pytest.raises(ValueError, match=r"good\.csv: the row at 10° and 500 nm \(series ''\) repeats one of "
                                         r".*bad\.csv"):
        import_files([bad, good], ImportSpec(units="percent"))
    # gonio brdf data with a gloss peak above 1.5 is not percent (median of the series)
    gonio = write(tmp_path / "g.csv", "angle_deg,angle_out_deg,phi_deg,wavelength_nm,reflectance,sigma,geometry\n"
                                      "30,30,0,550,4.44,0.044,brdf\n30,45,90,550,0.0105,0.0002,brdf\n"
                                      "30,60,180,550,0.0039,0.0001,brdf\n")
    assert len(read_csv(gonio)) == 3
    # ... but off-specular factors in percent are: a gonio set at 20-30 % (median 25 > 1.5),
    # while the gloss row (within 15° of the mirror) is left out of the median. Mutation caught:
    # including the mirror row and excluding none lets a 1-row off-specular set decide alone.
    pct = write(tmp_path / "p.csv", "angle_deg,angle_out_deg,phi_deg,wavelength_nm,reflectance,sigma,geometry\n"
                                    "30,30,0,550,0.9,0.1,brdf\n30,0,0,550,25,0.5,brdf\n30,60,180,550,20,0.5,brdf\n"
                                    "30,45,90,550,30,0.5,brdf\n")
    with pytest.raises(ValueError, match=r"p\.csv: line 5: column reflectance: the values look like percent "
                                         r"\(off-specular diffuse/brdf reflectance factors with median 25"):
        read_csv(pct)


def test_series_column_round_trip(tmp_path):
    text = ("angle_deg,wavelength_nm,reflectance,sigma,geometry,series\n"
            "10,500,0.2,0.01,specular,a\n10,500,0.3,0.01,specular,b\n")
    ds = read_csv(write(tmp_path / "s.csv", text))
    assert ds.series_names() == ["a", "b"] and [g for g, _ in ds.groups()] == ["a: specular 10°", "b: specular 10°"]
    back = tmp_path / "back.csv"
    ds.write_csv(back)
    assert read_csv(back).series.tolist() == ["a", "b"]


def test_several_files_one_per_angle_with_replicates(tmp_path):
    """Files named by angle (name_pattern with a replicate label) averaged per angle, SE from numpy."""
    values = {15: [0.20, 0.22], 30: [0.25, 0.24]}
    paths = []
    for angle, reps in values.items():
        for k, v in enumerate(reps):
            paths.append(write(tmp_path / f"scale_{angle}deg_{k}.csv", f"wl,R\n400,{v}\n500,{v + 0.01}\n"))
    spec = parse_spec({"geometry": "specular", "name_pattern": r"scale_(?P<angle>\d+)deg_"}, "test sidecar")
    ds, _ = import_files(paths, spec)
    for angle, reps in values.items():
        rows = ds.angle_deg == angle
        np.testing.assert_allclose(ds.reflectance[rows], np.mean(reps) + np.array([0, 0.01]), rtol=1e-9, atol=0)
        np.testing.assert_allclose(ds.sigma[rows], np.std(reps, ddof=1) / np.sqrt(2), rtol=1e-5, atol=0)


def test_reference_spectrum_file(tmp_path):
    ref = write(tmp_path / "spectralon.csv", "wavelength_nm,reflectance\n390,98\n510,96\n")
    data = write(tmp_path / "w.csv", "wavelength_nm,R_20deg\n400,0.5\n500,0.6\n")
    side = write(tmp_path / "w.csv.toml", 'geometry = "specular"\n[sigma]\nrelative = 0.01\n'
                                          '[reference]\nfile = "spectralon.csv"\nunits = "percent"\n')
    ds, _ = import_files([data], load_spec(side))
    expected = np.array([0.5, 0.6]) * np.interp([400, 500], [390, 510], [0.98, 0.96])
    np.testing.assert_allclose(ds.reflectance, expected, rtol=1e-9, atol=0)
    write(tmp_path / "w.csv.toml", 'geometry = "specular"\n[sigma]\nrelative = 0.01\n'
                                   '[reference]\nfile = "spectralon.csv"\n')
    with pytest.raises(ValueError, match=r"spectralon\.csv: column 2 'reflectance', line 2: the values look like "
                                         r"percent"):
        import_files([data], load_spec(tmp_path / "w.csv.toml"))
    assert os.path.exists(ref)


def run_cli(*args, cwd):
    env = dict(os.environ, BSDFLAB_THREADS="2", BSDFLAB_CACHE_DIR=str(cwd / ".cache"))
    return subprocess.run([sys.executable, "-m", "bsdflab.cli.main", "fit", "import", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def cli_in_process(capsys, monkeypatch, *args, cwd):
    """`bsdflab fit import ARGS...` as run_cli, in this process (bsdflab.cli.main.main with a
    list, as tests call it): (exit status, stdout, stderr), without a child's ~3 CPU-s of
    imports."""
    from bsdflab.cli.main import main

    monkeypatch.chdir(cwd)
    monkeypatch.setenv("BSDFLAB_CACHE_DIR", str(cwd / ".cache"))
    capsys.readouterr()
    status = main(["fit", "import", *args])
    out, err = capsys.readouterr()
    return status, out, err


def test_cli_import(tmp_path, capsys, monkeypatch):
    """The first run is the real program (a child process); the others call its main in this
    process. Mutation: the refusal of an existing --out dropped (cli/fit_import.py) fails it."""
    write(tmp_path / "angles.csv", WIDE)
    write(tmp_path / "angles.csv.toml", 'geometry = "specular"\n[sigma]\nabsolute = 0.2\n')
    r = run_cli("angles.csv", "--out", "data.csv", "--units", "percent", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "wrote 6 rows to data.csv (sidecar angles.csv.toml)" in r.stdout
    ds = read_csv(tmp_path / "data.csv")
    np.testing.assert_allclose(ds.reflectance[:3], [0.253, 0.26, 0.275], rtol=1e-9, atol=0)
    # undeclared percent: refused, exit status 2, nothing written
    status, _, err = cli_in_process(capsys, monkeypatch, "angles.csv", "--out", "other.csv", cwd=tmp_path)
    assert status == 2 and "look like percent" in err and "Traceback" not in err
    assert not (tmp_path / "other.csv").exists()
    # an existing --out is kept
    status, _, err = cli_in_process(capsys, monkeypatch, "angles.csv", "--out", "data.csv", "--units", "percent",
                                    cwd=tmp_path)
    assert status == 2 and "already exists" in err
    # options alone, no sidecar: --angles per column
    write(tmp_path / "plain.tsv", "nm\ta\tb\n500\t0.3\t0.4\n")
    status, _, err = cli_in_process(capsys, monkeypatch, "plain.tsv", "--out", "p.csv", "--geometry", "total",
                                    "--angles", "8,20", "--sigma-relative", "0.02", cwd=tmp_path)
    assert status == 0, err
    assert read_csv(tmp_path / "p.csv").angle_deg.tolist() == [8.0, 20.0]


@pytest.mark.parametrize("files, spec, match", [
    ({"w.csv": "wavelength_nm,a,b\n400,0.2,0.3\n"}, dict(geometry="specular", angles_deg=(10.0,), sigma_absolute=0.01),
     r"angles_deg gives 1 angles for 2 curves \(a, b\)"),
    ({"w.csv": "wavelength_nm,R_15deg\n400,0.2\n"}, dict(geometry="diffuse", sigma_absolute=0.01),
     r"column 2 'R_15deg': a diffuse curve needs angle_out_deg"),
    ({"w.csv": "wavelength_nm,R_15deg\n400,0.2\n"}, dict(geometry="diffuse", angle_out_deg=15.0, sigma_absolute=0.01),
     r"a diffuse curve at the mirror direction"),
    ({"w.csv": "wavelength_nm,R_95deg\n400,0.2\n"}, dict(geometry="specular", sigma_absolute=0.01),
     r"angle of incidence must be in \[0, 90\), got 95"),
    ({"w.xyz": "x"}, dict(geometry="specular"), r"w\.xyz: cannot tell the format from the suffix '\.xyz'"),
    ({"a.csv": "angle_deg,wavelength_nm,reflectance,sigma,geometry\n10,500,0.2,0.01,specular\n",
      "b.csv": "wavelength_nm,R_15deg\n400,0.2\n"}, dict(sigma_absolute=0.01), r"cannot mix the long CSV"),
    ({"a.csv": "wavelength_nm,R_15deg\n400,0.2\n410,0.3\n", "b.csv": "wavelength_nm,R_20deg\n400,0.2\n420,0.3\n"},
     dict(geometry="specular", sigma_absolute=0.01), r"b\.csv: column 2 'R_20deg': its wavelengths differ"),
    ({"w.csv": "wavelength_nm,R_15deg\n300,0.2\n340,0.3\n"}, dict(geometry="specular", sigma_absolute=0.01),
     r"no wavelength inside the model's range"),
    ({"w.csv": "wavelength_nm,R_15deg\n400,0.2\n410,0.3\n"},
     dict(geometry="specular", sigma_absolute=0.01, wavelengths=np.array([400.0, 420.0])),
     r"covers 400-410 nm, the grid asks for 400-420 nm"),
    ({"w.csv": "wavelength_nm,R_15deg\n400,0.2\n"}, dict(format="procspec", geometry="specular"),
     r"w\.csv: not a readable ProcSpec \(zip\) archive"),
])
def test_bad_imports(tmp_path, files, spec, match):
    paths = [write(tmp_path / name, text) for name, text in files.items()]
    with pytest.raises(ValueError, match=match):
        import_files(paths, ImportSpec(**spec))


def test_stem_sidecar_and_comments_kept(tmp_path):
    from bsdflab.fit.readers import default_sidecar

    data = write(tmp_path / "run.csv", "# truth: film_thickness_nm=430\nwavelength_nm,R_15deg\n400,0.2\n")
    assert default_sidecar(data) is None
    side = write(tmp_path / "run.toml", 'geometry = "total"\n[sigma]\nabsolute = 0.01\n')
    assert default_sidecar(data) == side
    write(tmp_path / "run.csv.toml", 'geometry = "specular"\n')
    assert default_sidecar(data) == str(tmp_path / "run.csv.toml")
    ds, _ = import_files([data], load_spec(side))
    assert ds.comments[0] == "truth: film_thickness_nm=430" and ds.geometry.tolist() == [2]


def test_the_shipped_wide_example_imports_to_852_rows():
    """examples/fit/wide: 12 angles x 71 wavelengths, two replicates each, percent relative
    to a 0.99 standard; the first row checked against the file's own cells."""
    here = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "fit", "wide")
    path = os.path.join(here, "angles.csv")
    ds, notes = import_files([path], load_spec(path + ".toml"))
    assert len(ds) == 852 and sorted(set(ds.angle_deg)) == list(range(15, 71, 5))
    with open(path, encoding="utf-8") as f:
        row = [ln for ln in f if not ln.startswith("#")][1].split(",")
    a, b = float(row[1]), float(row[2])
    np.testing.assert_allclose(ds.reflectance[0], (a + b) / 2 / 100 * 0.99, rtol=1e-9, atol=0)
    np.testing.assert_allclose(ds.sigma[0], np.hypot(abs(a - b) / 2, 0.1) / 100 * 0.99, rtol=1e-5, atol=0)
    assert any(c.startswith("truth:") for c in ds.comments)
