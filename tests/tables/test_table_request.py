"""One table request (bsdflab/tables/request.py): every form reads to the same request, one
default and one validation, the cache key of the code before it, the method chosen
automatically, ``tables.get``, and the tabulator built once per table (bit-identical)."""
from __future__ import annotations

import hashlib
import subprocess

import numpy as np
import pytest

import bsdflab as bl
from bsdflab import _core
from bsdflab.presets import preset
from bsdflab.tables import TableGrid, TableRequest, get, stages, tabulate
from bsdflab.tables.deterministic import TABLE_RULES
from bsdflab.tables.file_format import canonical_json
from support.cli import BSDFLAB

WL = [450.0, 550.0, 650.0]
GRID = TableGrid(2, 3, 2, thickness_nm=(360.0, 400.0))
SNAKE = preset("xenopeltis")
DIFFUSE = {"type": "diffuse", "reflectance": 0.5}


def sha(content: dict) -> str:
    return hashlib.sha256(canonical_json(content).encode("utf-8")).hexdigest()


def test_01_keys_are_the_documented_hash_of_the_old_content():
    """The key is SHA-256 of the canonical JSON of the content the cache keyed before this
    type (written out here by hand, docs/table_format.md): tables cached before stay valid.
    Mutations caught: a method entry in a PFMC request's content, a seed in an adding-
    doubling one, or any renamed field changes the hash."""
    model = SNAKE.to_dict()
    common = {"channels": ["450", "550", "650"], "format_version": 3, "grid": GRID.to_dict(), "model": model,
              "rel_error": 0.02}
    pfmc = TableRequest.make(SNAKE, GRID, 0.02, WL, "pfmc", 64, 128, 3)
    assert pfmc.key() == sha({**common, "min_samples": 64, "max_samples": 128, "seed": 3, "error_floor": 0.05,
                              "estimator_version": int(_core.estimator_version)})
    solver = {"nodes": 16, "orders": None, "thin_depth": 2.0 ** -16, "order_tolerance": 1e-6, "film_lookup": True,
              "azimuth_samples": None, "spectral_stride": 1, "fine_step": 0.25, "table_settings": TABLE_RULES}
    ad = TableRequest.make(SNAKE, GRID, 0.02, WL, seed=9)
    assert ad.method == "adding-doubling" and ad.key() == sha({**common, "method": "adding-doubling",
                                                                "solver": solver})
    finer = TableRequest.make(SNAKE, GRID, 0.02, WL, nodes=24, orders=40)
    assert finer.key() == sha({**common, "method": "adding-doubling", "solver": {**solver, "nodes": 24,
                                                                                  "orders": 40}})


def test_02_every_form_reads_to_one_request_with_one_default():
    """The CLI's (make), a job's, a normalised and a render's form give equal requests and
    keys, and one default target (old: 0.01 in the CLI and jobs, 0.02 in renders)."""
    grid = GRID.to_dict()
    made = TableRequest.make(SNAKE, GRID)
    job = TableRequest.from_dict({"model": SNAKE.to_dict(), "grid": grid})
    render = TableRequest.from_dict({"type": "tabulated", "model": SNAKE.to_dict(), "grid": grid})
    again = TableRequest.from_dict(job.to_dict())
    assert made == job == render == again and len({r.key() for r in (made, job, render, again)}) == 1
    assert made.rel_error == 0.01 and made.method == "adding-doubling"
    partial = TableRequest.from_dict({"model": DIFFUSE, "grid": {"n_theta_i": 3}})   # grid defaults filled in
    assert partial.grid == TableGrid(3, TableGrid().n_theta_o, TableGrid().n_phi)


@pytest.mark.parametrize("field, value, message", [
    ("rel_error", 0.0, "rel_error must be"), ("rel_error", "x", "rel_error must be"),
    ("min_samples", 0, "min_samples must be"), ("max_samples", 2, r"max_samples \(2\) must be >= min_samples"),
    ("seed", -1, "seed must be"), ("method", "exact", "method must be one of auto, pfmc, adding-doubling"),
    ("nodes", 2, "nodes must be"), ("wavelengths", [0.0], "wavelengths must be"),
    ("grid", {"n_theta_i": 1}, "n_theta_i"), ("colour", 1, "unknown table request fields: colour"),
])
def test_03_each_setting_is_refused_by_name_in_every_form(field, value, message):
    for d in ({"model": DIFFUSE}, {"type": "tabulated", "model": DIFFUSE}):
        with pytest.raises(ValueError, match=message):
            TableRequest.from_dict({**d, field: value})


def test_04_the_method_is_chosen_and_said():
    """auto: adding-doubling where the solver covers the model, else PFMC with the reason."""
    assert TableRequest.make(SNAKE).method_note == "automatic: the solver covers this model"
    # a rough base under a smooth interior interface between unequal indices: the solver
    # refuses its pairs below ([rough-exit]), so its two-sided table is PFMC's
    transmits = bl.Layered([bl.Dielectric(1.5, 1.0), bl.Dielectric(1.7, 1.5)],
                           [bl.Slab(1.0, sigma_s=1.0), bl.Slab(1.0, sigma_s=1.0)], bl.RoughDielectric(0.3, 1.0, 1.7))
    too_smooth = bl.Layered([bl.RoughDielectric(1e-4, 1.5, 1.0)], [bl.Slab(1.0)], bl.Diffuse(0.5))
    for model, why in ((bl.Diffuse(0.5), "Layered models, not Diffuse"), (transmits, "transmits"),
                       (too_smooth, "interfaces[0].alpha must be in")):
        r = TableRequest.make(model)
        assert r.method == "pfmc" and r.method_note.startswith("automatic: adding-doubling does not cover")
        assert why in r.method_note
        with pytest.raises(ValueError, match="cannot tabulate this model"):
            TableRequest.make(model, method="adding-doubling")
    assert TableRequest.make(SNAKE, method="pfmc").method == "pfmc"
    with pytest.raises(ValueError, match="nodes and orders are the adding-doubling solver's"):
        TableRequest.make(bl.Diffuse(0.5), nodes=20)


def test_05_get_reads_the_cache_and_false_skips_it(tmp_path):
    request = TableRequest.make(SNAKE, GRID, 0.05, WL)
    first = get(request, cache=tmp_path)
    second = get(request, cache=tmp_path)
    assert not first.from_cache and second.from_cache and first.path == second.path
    assert first.path.name == f"{request.key()}.exr" and first.table.meta["method"] == "adding-doubling"
    np.testing.assert_array_equal(first.table.values, second.table.values)
    fresh = get(request, cache=False)
    assert fresh.path is None and not fresh.from_cache and list(tmp_path.iterdir()) == [first.path]


def test_06_the_tabulator_is_built_once_and_the_table_is_bit_identical(monkeypatch):
    """One core Tabulator per table (old: four per table, one per stage and one for the
    film-lookup error); the stages share it through ``with_settings``. Against a fresh
    build for every stage (the old behaviour) values, errors and sample counts are equal
    bit for bit. Mutation caught: ``with_settings`` returning the shared tabulator
    unchanged (the finish would run at the pilot's settings: other sample counts)."""
    model = preset("xenopeltis", samples=8)
    kw = dict(rel_error=0.2, wavelengths=WL, min_samples=16, max_samples=64, seed=5, progress=False,
              method="pfmc")
    built = []
    original = stages._build_tabulator
    monkeypatch.setattr(stages, "_build_tabulator", lambda *a: built.append(1) or original(*a))
    shared = tabulate(model, GRID, **kw)
    assert len(built) == 1
    monkeypatch.setattr(stages, "_built", _Forgetful())  # a fresh tabulator for every stage
    fresh = tabulate(model, GRID, **kw)
    assert len(built) >= 4
    for name in ("values", "stderr", "samples"):
        np.testing.assert_array_equal(getattr(shared, name), getattr(fresh, name), err_msg=name)
    assert int(shared.samples.max()) > 16   # the finish ran at its own settings


class _Forgetful(dict):
    def __setitem__(self, key, value):  # remembers nothing
        pass

    def get(self, key, default=None):
        return default


def test_07_settings_are_bound_by_keyword_only():
    """The core's TabulationSettings, Tabulator, LayeredOptions and LayeredBSDF take their
    settings by keyword (old: 14 and 13 positional arguments; min and max samples in
    swapped order at the tabulator's call site)."""
    with pytest.raises(TypeError):
        _core.TabulationSettings(0.01, 0.05, 16, 64, 0, True)
    s = _core.TabulationSettings(rel_error=0.01, floor=0.05, min_samples=16, max_samples=64, seed=0)
    assert (s.min_samples, s.max_samples, s.film_lookup) == (16, 64, True)
    with pytest.raises(ValueError, match="min_samples <= max_samples"):
        _core.TabulationSettings(rel_error=0.01, floor=0.05, min_samples=64, max_samples=16, seed=0)
    with pytest.raises(TypeError):
        _core.Tabulator(bl.Diffuse(0.5)._core(np.array(WL)), 1, 2, 2, 2, [], [1.0] * 6, 2, s)
    with pytest.raises(TypeError):
        _core.LayeredOptions(16, 0, 64)
    o = _core.LayeredOptions(samples=16, seed=3, max_depth=64)
    assert (o.samples, o.seed, o.max_depth, o.nee, o.pdf_samples, o.estimator) == (16, 3, 64, True, 1, 1)
    with pytest.raises(ValueError, match="pdf_samples"):
        _core.LayeredOptions(samples=16, seed=3, max_depth=64, pdf_samples=-1)
    wl = np.array(WL)
    parts = [bl.Dielectric(1.5, 1.0)._core(wl), bl.Diffuse(0.5)._core(wl)]
    with pytest.raises(TypeError):
        _core.LayeredBSDF(list(wl), parts, [1.0], [[0.0] * 3], [0.0], [0], [0.0], 16, 0, 64, True)


def test_08_cli_says_which_method_and_why(tmp_path):
    common = ["--theta-i", "2", "--theta-o", "3", "--phi", "2", "--wavelengths", *map(str, WL), "--quiet",
              "--cache-dir", str(tmp_path)]
    ad = subprocess.run([*BSDFLAB, "tabulate", "--preset", "xenopeltis", *common], capture_output=True,
                        text=True, timeout=300)
    assert ad.returncode == 0, ad.stderr
    assert "method        adding-doubling (automatic: the solver covers this model)" in ad.stdout
    pf = subprocess.run([*BSDFLAB, "tabulate", "--preset", "xenopeltis-diffuse", *common], capture_output=True,
                        text=True, timeout=300)
    assert pf.returncode == 0, pf.stderr
    assert "method        pfmc (automatic: adding-doubling does not cover this model (it tabulates Layered" \
        in pf.stdout
