"""`bsdflab export` on the command line: a real process, one-line errors, exit 2, no partial files."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest


def _run(*argv, cwd=None):
    return subprocess.run([sys.executable, "-m", "bsdflab.cli.main", "export", *argv], capture_output=True,
                          text=True, timeout=600, cwd=cwd)


def test_export_preset_with_set_writes_file_and_report(tmp_path):
    out = tmp_path / "snake.glb"
    proc = _run("--preset", "xenopeltis", "--set", "film_thickness_nm=450", "--format", "gltf", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    assert sorted(os.listdir(tmp_path)) == ["snake.glb", "snake.glb.report.json", "snake.glb.report.png"]
    report = json.load(open(str(out) + ".report.json"))
    assert report["material"]["film_thickness_nm"] == 450.0
    assert "Delta E00" in proc.stdout


@pytest.mark.parametrize("argv, needle", [
    (["--json", '{"type": "diffuse", "reflectance": 0.5}', "--format", "openpbr"], "nothing exportable"),
    (["--preset", "xenopeltis-stack", "--format", "openpbr"], "film stack of 9 layers"),  # without --substitute
    (["--preset", "xenopeltis", "--format", "fbx"], "unknown format"),
    (["--preset", "xenopeltis", "--format", "gltf"], "must end in .gltf or .glb"),
])
def test_bad_input_is_one_line_exit_2_and_no_files(tmp_path, argv, needle):
    proc = _run(*argv, "--out", str(tmp_path / "x.mtlx"))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bsdflab export: error:") and needle in lines[0], proc.stderr
    assert os.listdir(tmp_path) == []


def test_unwritable_out_is_refused(tmp_path):
    """Root writes anywhere (CI runs as root): there the read-only folder's run, a whole
    export that nothing checks, is not made, and the missing folder covers the refusal.
    Mutation: the out folder's checks dropped (export/exporter.py) fails it."""
    folder = tmp_path / "ro"
    folder.mkdir()
    os.chmod(folder, 0o500)
    try:
        if os.geteuid() != 0:
            proc = _run("--preset", "xenopeltis", "--format", "openpbr", "--out", str(folder / "x.mtlx"))
        missing = _run("--preset", "xenopeltis", "--format", "openpbr", "--out", str(tmp_path / "no" / "x.mtlx"))
    finally:
        os.chmod(folder, 0o700)
    if os.geteuid() != 0:
        assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1
        assert os.listdir(folder) == []
    assert missing.returncode == 2 and len(missing.stderr.strip().splitlines()) == 1, missing.stderr
    assert not (tmp_path / "no").exists()


def test_export_from_a_table_uses_the_model_its_header_records(tmp_path):
    from bsdflab.bsdfs import RoughDielectric
    from bsdflab.tables import TableGrid, tabulate
    from bsdflab.tables.file_format import write_table

    model = RoughDielectric(0.1, 1.5515, 1.0, film=[{"material": 1.8, "thickness_nm": 350.0}])
    table = tmp_path / "t.exr"
    write_table(table, tabulate(model, TableGrid(3, 4, 2), progress=False))
    out = tmp_path / "m.mtlx"
    proc = _run("--table", str(table), "--format", "openpbr", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    report = json.load(open(str(out) + ".report.json"))
    assert report["material"]["film_thickness_nm"] == 350.0 and report["material"]["film_ior"] == 1.8
    assert report["material"]["alpha"] == 0.1


def test_a_stack_is_exported_only_as_a_substitute_that_states_its_error(tmp_path):
    out = tmp_path / "stack.mtlx"
    proc = _run("--preset", "xenopeltis-stack", "--substitute", "--format", "openpbr", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    report = json.load(open(str(out) + ".report.json"))
    assert any("9-layer film stack" in d for d in report["dropped"])
    assert len(report["material"]["stack"]) == 9
    # a 5-platelet reflector is far brighter than any single film: the report must say so
    assert report["delta_e00"]["share_above_2"] > 0.5
