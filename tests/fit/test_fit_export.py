"""A fit study's material.json goes on: it exports (``bsdflab export --json material.json``)
and renders (``bsdflab render sphere.json``). The fit writes its film as a Cauchy index;
with B = 0 that is a constant index, which the exporters take as it is."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from bsdflab import from_dict
from bsdflab.export.material import export_material
from bsdflab.fit.config import ModelSettings
from bsdflab.fit.material import material_dict
from bsdflab.fit.parameters import ALL, ALL_NAMES


def fitted(model: ModelSettings, **kw) -> dict:
    v = {n: ALL[n].default for n in ALL_NAMES}
    v.update(kw)
    return from_dict(material_dict(v, model=model)).to_dict()    # the canonical form a study writes


def cli(*argv, **kw):
    return subprocess.run([sys.executable, "-m", "bsdflab.cli.main", *argv], capture_output=True, text=True,
                          timeout=600, **kw)


@pytest.mark.parametrize("model", [ModelSettings(), ModelSettings(kind="full")])
def test_fit_material_is_exportable(model):
    """Cauchy B = 0: the film index is A exactly, nothing about dispersion dropped (the issue's
    "a spectral or named index cannot be exported" was this case). B != 0: n(550 nm) with the
    dispersion listed as dropped. An absorbing film index is still refused."""
    m = export_material(fitted(model, film_ior=1.77, film_thickness_nm=412.0))
    assert m.film_ior == 1.77 and m.film_thickness_nm == 412.0
    assert not [d for d in m.dropped if "dispersion" in d]
    assert m.alpha == (ALL["roughness"].default if model.kind == "full" else 0.0)
    m = export_material(fitted(model, film_ior=1.77, film_cauchy_b=6000.0))
    assert np.isclose(m.film_ior, 1.77 + 6000.0 / 550.0**2, rtol=1e-12, atol=0)
    assert [d for d in m.dropped if d.startswith("film material: dispersion")]
    absorbing = fitted(model)
    absorbing["interfaces"][0]["film"][0]["material"] = {"type": "constant", "n": 1.8, "k": 0.1}
    with pytest.raises(ValueError, match="absorbing index"):
        export_material(absorbing)


def test_study_material_exports_and_renders(tmp_path):
    """The CLI path a user takes: ``bsdflab export --json material.json`` (a file, not only a
    JSON string) writes the target file and its report; the study's sphere.json renders."""
    from bsdflab.fit.renders import sphere_scene
    from bsdflab.scenes.scene_file import save_scene

    path = tmp_path / "material.json"
    path.write_text(json.dumps(fitted(ModelSettings())))
    r = cli("export", "--json", str(path), "--format", "openpbr", "--out", str(tmp_path / "m.mtlx"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "m.mtlx").is_file() and (tmp_path / "m.mtlx.report.json").is_file()
    r = cli("export", "--json", str(tmp_path / "missing.json"), "--format", "openpbr",
            "--out", str(tmp_path / "x.mtlx"))
    assert r.returncode == 2 and "neither a JSON dict nor a readable file" in r.stderr
    values = np.array([ALL[n].default for n in ALL_NAMES])
    save_scene(sphere_scene(values, 16), tmp_path / "sphere.json")
    r = cli("render", str(tmp_path / "sphere.json"), "--spp", "1", "--width", "12", "--height", "12", "--quiet",
            "--out", str(tmp_path / "sphere.exr"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "sphere.png").is_file()


@pytest.mark.slow
@pytest.mark.parametrize("fmt, ext", [("openpbr", "mtlx"), ("usd", "usda"), ("gltf", "glb"), ("blender", "blend")])
def test_full_model_material_exports_to_every_format(tmp_path, fmt, ext):
    path = tmp_path / "material.json"
    path.write_text(json.dumps(fitted(ModelSettings(kind="full"))))
    r = cli("export", "--json", str(path), "--format", fmt, "--out", str(tmp_path / f"m.{ext}"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / f"m.{ext}").is_file()
