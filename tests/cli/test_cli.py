"""The `bsdflab` command as a user runs it: a real process writing real files."""
import os
import subprocess
import sys

import pytest

BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]


def run(*args, **kw):
    return subprocess.run([*BSDFLAB, *args], capture_output=True, text=True, timeout=120, **kw)


@pytest.mark.parametrize("args", [["--help"], ["lobe", "--help"], ["info", "--help"]])
def test_01_help_everywhere(args):
    r = run(*args)
    assert r.returncode == 0 and "usage:" in r.stdout


@pytest.mark.parametrize("material", [
    ["--material", "diffuse", "--reflectance", "0.8", "0.4", "0.2"],
    ["--material", "conductor", "--metal", "Cu"],
    ["--material", "dielectric", "--int-ior", "1.5"],
])
def test_02_lobe_writes_a_png(tmp_path, material):
    out = tmp_path / "sub" / "lobe.png"
    r = run("lobe", *material, "--theta-i", "40", "--samples", "20000", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "albedo_R" in r.stdout
    assert not [p for p in os.listdir(out.parent) if p.endswith(".tmp")]


@pytest.mark.parametrize("args, match", [
    (["lobe", "--theta-i", "95"], "--theta-i must be < 90"),
    (["lobe", "--material", "conductor", "--metal", "Zz"], "unknown metal"),
    (["lobe", "--reflectance", "2"], "reflectance must be <= 1"),
    (["lobe", "--json", "{not json"], "not valid JSON"),
])
def test_03_bad_input_is_a_message_not_a_traceback(tmp_path, args, match):
    r = run(*args, "--out", str(tmp_path / "x.png"))
    assert r.returncode == 2
    assert match in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "x.png").exists()


def test_04_info():
    r = run("info")
    assert r.returncode == 0 and "Johnson" in r.stdout
