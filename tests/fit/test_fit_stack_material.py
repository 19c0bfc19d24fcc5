"""A smooth structure study's material.json (bsdflab.fit.stack_material): the renderable
model reproduces the fitted stack's specular reflectance, exports to every format and renders.

The reflectance is read through bsdflab's own model API (``from_dict(...).exact_part``'s
delta-reflection sample: the top interface's Fresnel term with its film,
bsdflab/bsdfs/interface_term.py), not the fit's forward code (the core's film_stack through
_core.InstrumentStack); both are exact, so they agree to round-off (1e-12 absolute, R <= 1).
"""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from bsdflab.bsdfs import from_dict
from bsdflab.fit.data import Dataset
from bsdflab.fit.stack_config import StackConfig
from bsdflab.fit.stack_forward import StackForward
from bsdflab.fit.stack_material import stack_material_dict, stack_material_note
from bsdflab.fit.stack_study import run_stack_study
from bsdflab.fit.structure import Structure
from bsdflab.lobes import Lobe
from support.cli import cli_in_process

ANGLES, WLS = [0.0, 30.0, 55.0, 75.0], [352.5, 401.0, 477.0, 550.0, 633.3, 700.0]

STRUCTURES = {
    # the worked example's: film on a substrate, constant indices, a thickness spread (dropped)
    "film": {"substrate": {"n": 1.55}, "layers": [
        {"name": "film", "material": {"n": 1.83}, "thickness_nm": 430.0, "thickness_spread_nm": 12.0}]},
    # Cauchy and absorbing layers, a periodic block, off-grid wavelengths
    "periodic": {"exterior": {"n": 1.0}, "substrate": {"n": 1.517}, "layers": [
        {"name": "top", "material": {"cauchy": [1.45, 4000.0]}, "thickness_nm": 70.0},
        {"periods": 3, "layers": [{"name": "plate", "material": {"n": 1.6, "k": 0.02}, "thickness_nm": 90.0},
                                  {"name": "gap", "material": "cytoplasm", "thickness_nm": 120.0}]}]},
}


def specular(angles, wavelengths) -> Dataset:
    n = len(angles) * len(wavelengths)
    return Dataset(np.zeros(n, int), np.repeat(np.asarray(angles, float), len(wavelengths)), np.full(n, np.nan),
                   np.tile(np.asarray(wavelengths, float), len(angles)), np.zeros(n), np.ones(n))


def defaults(s: Structure) -> dict:
    return {p.name: p.default for p in s.parameters()}


def material_reflectance(model: dict, angles, wavelengths) -> np.ndarray:
    """R (angles x wavelengths, row order of ``specular``) of the model's specular beam."""
    top = from_dict(model).exact_part
    out = []
    for a in angles:
        t = np.radians(a)
        s = top.sample(np.array([[np.sin(t), 0.0, np.cos(t)]]), wavelengths=np.asarray(wavelengths),
                       lobes=Lobe.DELTA_REFLECTION)
        out.append(s.weight[0])
    return np.concatenate(out)


@pytest.mark.parametrize("key", STRUCTURES)
def test_material_reflects_as_the_fitted_stack(key):
    """material.json's specular R = the smooth model's prediction without instrument at spread
    0 (the mean thickness), to round-off; nothing else comes back (the black base: eval = 0
    off the mirror). Mutation caught: the film written bottom-up (misses by > 1e-2 on the
    periodic stack)."""
    s = Structure.parse(STRUCTURES[key])
    v = defaults(s)
    model = from_dict(stack_material_dict(s, v)).to_dict()      # the canonical form the study writes
    got = material_reflectance(model, ANGLES, WLS)
    sharp = {**v, **{n: 0.0 for n in v if n.endswith("_thickness_spread_nm")}}
    want = StackForward(specular(ANGLES, WLS), s).exact(lambda n: np.array([sharp[n]]), [0.0], [0.0], [0.0])[0]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    wi = np.array([[0.3, 0.0, 0.954], [0.0, 0.6, 0.8]])
    wo = np.array([[0.1, 0.2, 0.975], [0.5, -0.1, 0.86]])
    assert np.all(from_dict(model).eval(wi / np.linalg.norm(wi, axis=1)[:, None],
                                        wo / np.linalg.norm(wo, axis=1)[:, None]) == 0.0)


def test_material_note_says_what_is_left_out():
    s = Structure.parse(STRUCTURES["film"])
    note = stack_material_note(s, defaults(s))
    assert "film is a spatial average" in note and "mean thickness" in note and "instrument" in note
    keratin = Structure.parse({"substrate": "keratin", "layers": [
        {"name": "film", "material": "guanine", "thickness_nm": 400.0}]})
    note = stack_material_note(keratin, defaults(keratin))
    assert "substrate index is dispersive" in note and "spatial" not in note


def cli(*argv, **kw):
    return subprocess.run([sys.executable, "-m", "bsdflab.cli.main", *argv], capture_output=True, text=True,
                          timeout=600, **kw)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """A short smooth structure study (film thickness and spread free) on data of the model
    itself: its material.json and summary. No test here reads a figure: [output] figures =
    false (test_study_writes_material_json checks that no PNG was written)."""
    out = tmp_path_factory.mktemp("stack_material") / "study"
    s = Structure.parse(STRUCTURES["film"])
    angles, wls = [20.0, 50.0], np.arange(400.0, 701.0, 20.0)
    truth = defaults(s)
    y = StackForward(specular(angles, wls), s).exact(lambda n: np.array([truth[n]]), [0.0], [0.0], [0.0])[0]
    data = specular(angles, wls)
    data = Dataset(data.geometry, data.angle_deg, data.angle_out_deg, data.wavelength_nm, y, np.full(len(y), 2e-3))
    config = StackConfig.parse({
        "structure": STRUCTURES["film"],
        "parameters": {"film_thickness_nm": {"prior": "uniform", "low": 400.0, "high": 460.0},
                       "film_thickness_spread_nm": {"prior": "uniform", "low": 0.0, "high": 30.0}},
        "sampler": {"walkers": 8, "max_steps": 300, "check_every": 100, "map_starts": 2, "seed": 3},
        "output": {"figures": False}})
    summary = run_stack_study(config, out, data=data, progress=False)
    return out, summary


def test_study_writes_material_json(study):
    """material.json at the posterior median; [output] figures = false writes no PNG and the
    rest of the folder. Mutation: [output] ignored by run_stack_study (the PNGs written)
    fails it."""
    out, summary = study
    written = set(p.name for p in out.iterdir())
    assert {"parameters.csv", "draws.npz", "summary.json", "material.json"} <= written
    assert not [name for name in written if name.endswith(".png")], written
    model = json.loads((out / "material.json").read_text())
    assert model["type"] == "layered" and model["base"]["reflectance"] == {"type": "constant", "value": 0.0}
    median = {r["parameter"]: r["median"] for r in summary["parameters"]}
    assert model["interfaces"][0]["film"][0]["thickness_nm"] == pytest.approx(median["film_thickness_nm"],
                                                                            rel=1e-12)
    assert "mean thickness" in summary["material_note"]
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk["material_note"] == summary["material_note"]


@pytest.mark.parametrize("fmt, ext", [("openpbr", "mtlx"), ("usd", "usda"), ("gltf", "glb"), ("blender", "blend")])
def test_study_material_exports_to_every_format(study, tmp_path, capsys, monkeypatch, fmt, ext):
    """`bsdflab export` of the study's material.json to each format: openpbr as a real
    process, the others in-process (support.cli.cli_in_process: the same main() and
    exporters, without a child's ~3-4 CPU-s of imports each; blender's was 9)."""
    out, _ = study
    args = ("export", "--json", out / "material.json", "--format", fmt, "--out", tmp_path / f"m.{ext}")
    r = cli(*map(str, args)) if fmt == "openpbr" else cli_in_process(capsys, monkeypatch, *args)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / f"m.{ext}").is_file()
    report = json.loads((tmp_path / f"m.{ext}.report.json").read_text())
    assert report


def test_study_material_renders(study, tmp_path):
    out, _ = study
    r = cli("render", "sphere", "-o", "variant=diffuse", "-o", f"material={(out / 'material.json').read_text()}",
            "--width", "12", "--height", "12", "--spp", "1", "--quiet", "--out", str(tmp_path / "sphere.exr"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "sphere.png").is_file()


def test_one_walk_is_exact_for_eval_sample_and_pdf():
    """The black base ends every walk, so material.json's one walk (stack_material.SAMPLES) is
    exact: eval is exactly 0 for 4000 random pairs from above, grazing (cos 1e-9..1e-3) and
    below; sample and pdf do not read ``samples`` (bit-identical to 256 walks), and every
    sample off the top's delta reflection carries weight exactly 0, so a render that uses them
    is unbiased. Mutation caught: a base reflectance of 0.01 gives eval > 0."""
    s = Structure.parse(STRUCTURES["film"])
    d = stack_material_dict(s, defaults(s))
    one, many = from_dict(d), from_dict({**d, "samples": 256})
    rng = np.random.default_rng(7)

    def dirs(n, lo, hi):
        z, phi = rng.uniform(lo, hi, n), rng.uniform(0.0, 2.0 * np.pi, n)
        r = np.sqrt(1.0 - z * z)
        return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    wi = np.concatenate([dirs(1000, 1e-6, 1.0), dirs(1000, 1e-9, 1e-3), dirs(2000, -1.0, -1e-6)])
    wo = dirs(4000, -1.0, 1.0)
    assert np.all(one.eval(wi, wo) == 0.0) and np.all(one.eval(wi, wi * [-1.0, -1.0, 1.0]) == 0.0)
    assert np.array_equal(one.pdf(wi, wo), many.pdf(wi, wo))
    a, b = one.sample(wi), many.sample(wi)
    for key in ("wo", "weight", "pdf", "lobe", "eta"):
        assert np.array_equal(np.asarray(getattr(a, key)), np.asarray(getattr(b, key)), equal_nan=True), key
    off = np.asarray(a.lobe) != int(Lobe.DELTA_REFLECTION)
    assert np.all(np.asarray(a.weight)[off] == 0.0) and np.any(~off)
