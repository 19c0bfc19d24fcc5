"""`bsdflab render` end to end: real files, scene files, bad input, Ctrl-C."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

from bsdflab.cli.main import main
from bsdflab.render import read_exr
from bsdflab.scenes import scene
from bsdflab.scenes.scene_file import save_scene
from support.cli import interruptible, wait_for_cpu
from support.png_check import assert_png_shows_exr

BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]


def test_01_render_writes_exr_png_and_a_summary(tmp_path, capsys):
    out = tmp_path / "f.exr"
    rc = main(["render", "furnace", "--width", "16", "--height", "12", "--spp", "4", "--out", str(out), "--quiet"])
    assert rc == 0
    image = read_exr(out)
    assert image.shape == (12, 16, 3)
    assert abs(image.mean() - 1) < 0.05  # the white furnace: every pixel about 1
    assert_png_shows_exr(tmp_path / "f.png", image)  # mutation: a PNG of another image or size
    summary = json.loads(capsys.readouterr().out.split("\nwrote")[0])
    assert summary["spp"] == 4 and summary["samples_per_second"] > 0


def test_02_scene_file_renders_like_the_named_scene(tmp_path):
    path = tmp_path / "scene.json"
    save_scene(scene("basic-materials", width=12, height=9), path)
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    assert main(["render", "basic-materials", "-o", "width=12", "-o", "height=9", "--spp", "2",
                 "--out", str(a), "--quiet"]) == 0
    assert main(["render", str(path), "--spp", "2", "--out", str(b), "--quiet"]) == 0
    assert np.array_equal(read_exr(a), read_exr(b))


@pytest.mark.parametrize("args, message", [
    (["nosuch"], "unknown scene"),
    (["furnace", "--spp", "0"], "spp"),
    (["furnace", "--width", "0"], "width"),
    (["furnace", "--out", "x.png"], ".exr"),
    (["furnace", "-o", "colour"], "KEY=VALUE"),
    (["snake", "-o", "material=gold"], "material"),
    (["missing.json"], "missing.json"),
])
def test_03_bad_input_exits_2_with_a_message(args, message, tmp_path, capsys):
    rc = main(["render", *args, "--quiet"] + ([] if "--out" in args else ["--out", str(tmp_path / "o.exr")]))
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "o.exr").exists()


def test_04_interrupted_render_leaves_no_output(tmp_path):
    """SIGINT during a long render: non-zero exit without an abort, and no file at all. The
    signal goes once the render has spent a CPU-second (not after a wall-clock sleep);
    320 x 240 at 10^5 spp cannot finish first."""
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    with interruptible([*BSDFLAB, "render", "basic-materials", "-o", "width=320", "-o", "height=240",
                        "--spp", "100000", "--out", str(out_dir / "x.exr")],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        err = bytearray()
        started = threading.Event()

        def read():
            while chunk := os.read(proc.stderr.fileno(), 4096):
                err.extend(chunk)
                if b"rendering" in err:
                    started.set()

        threading.Thread(target=read, daemon=True).start()
        while not started.wait(0.05):  # hang guard only: the test's timeout
            assert proc.poll() is None, err.decode(errors="replace")
        wait_for_cpu(proc, 1.0, err.decode(errors="replace"))  # inside the render, at any load
        proc.send_signal(signal.SIGINT)
        rc = proc.wait(timeout=300)
    assert rc != 0 and rc not in (-signal.SIGABRT, -signal.SIGSEGV)
    assert os.listdir(out_dir) == []


def test_05_scene_set_becomes_a_labelled_contact_sheet(tmp_path):
    out = tmp_path / "grid.exr"
    assert main(["render", "appearance-grid", "--width", "8", "--height", "6", "--spp", "1", "--out", str(out),
                 "--quiet"]) == 0
    mosaic = read_exr(out)
    assert mosaic.shape == (2 * 6 + 4, 3 * 8 + 2 * 4, 3)  # 2 rows x 3 columns, 4-pixel gaps
    assert (tmp_path / "grid.png").stat().st_size > 0  # a labelled matplotlib sheet, not a tone map


def test_06_list_names_every_scene_and_set(capsys):
    assert main(["render", "--list", "x"]) == 0
    listed = capsys.readouterr().out
    for name in ("snake", "sphere", "torus", "basic-materials", "furnace", "appearance-grid", "ablation"):
        assert name in listed
