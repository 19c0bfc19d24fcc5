"""`bsdflab render ... -o light=...`: lights added from the command line, to named scenes and
scene files, and bad ones refused with the field named (exit 2)."""
from __future__ import annotations

import json

import pytest

from bsdflab.cli.main import main
from bsdflab.render import read_exr
from bsdflab.scenes import scene
from bsdflab.scenes.scene_file import load_scene, save_scene

POINT = '{"type": "point", "position": [0, 0, 3], "intensity": 4}'


def test_a_light_option_is_added_to_the_scene_and_saved(tmp_path):
    out, saved = tmp_path / "f.exr", tmp_path / "f.json"
    rc = main(["render", "furnace", "-o", f"light={POINT}", "--width", "8", "--height", "6", "--spp", "2",
               "--out", str(out), "--save-scene", str(saved), "--quiet"])
    assert rc == 0 and read_exr(out).shape == (6, 8, 3)
    lights = load_scene(saved).lights
    assert [lt.type for lt in lights] == ["point"] and lights[0].intensity == (4.0, 4.0, 4.0)


def test_a_bare_type_name_gives_its_defaults_and_scene_files_take_lights(tmp_path):
    path = tmp_path / "s.json"
    save_scene(scene("furnace", width=8, height=6), path)
    out, saved = tmp_path / "s.exr", tmp_path / "again.json"
    rc = main(["render", str(path), "-o", "light=sun", "-o", f"lights=[{POINT}]", "--spp", "2", "--out", str(out),
               "--save-scene", str(saved), "--quiet"])
    assert rc == 0
    assert [lt.type for lt in load_scene(saved).lights] == ["sun", "point"]
    assert json.loads(saved.read_text())["lights"][0]["elevation_deg"] == 35.0


@pytest.mark.parametrize("value, words", [
    ('light={"type": "point", "position": [0, 1, 0], "intensity": -1}', "intensity"),
    ('light={"type": "spot", "position": [0, 1, 0], "direction": [0, 0, 0], "intensity": 1}', "direction"),
    ("light=laser", "unknown light type"),
    ('lights={"type": "sun"}', "JSON list"),
])
def test_bad_lights_exit_2_naming_the_field(value, words, tmp_path, capsys):
    rc = main(["render", "furnace", "-o", value, "--spp", "2", "--out", str(tmp_path / "x.exr"), "--quiet"])
    assert rc == 2
    assert words in capsys.readouterr().err
