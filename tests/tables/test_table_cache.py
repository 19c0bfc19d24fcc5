"""The table cache: the key holds everything that changes a table (effort, seed, estimator
version), a cached file is checked to be the table requested, and `bsdflab tabulate` says
when the accuracy target is not met. Each test failed before its fix (noted beside it)."""
from __future__ import annotations

import json

import numpy as np

import bsdflab as bl
from bsdflab.tables import TableData, TableGrid, cache_key, cached_table, tabulate, write_table
from support.cli import cli
from support.tables import GRID, MODEL, valid_table


def test_cache_key_holds_effort_seed_and_estimator(monkeypatch):
    # old: cache_key took no max_samples / seed (TypeError), min_samples only when given
    base = cache_key(MODEL, GRID, 0.01, "rgb")
    assert base == cache_key(MODEL, GRID, 0.01, ("R", "G", "B"), 512, 65536, 0)  # defaults spelled out
    others = {cache_key(MODEL, GRID, 0.01, "rgb", min_samples=16),
              cache_key(MODEL, GRID, 0.01, "rgb", max_samples=1024),
              cache_key(MODEL, GRID, 0.01, "rgb", seed=7)}
    assert base not in others and len(others) == 3
    from bsdflab import _core
    monkeypatch.setattr(_core, "estimator_version", 99, raising=False)
    assert cache_key(MODEL, GRID, 0.01, "rgb") != base


def test_cached_table_with_another_seed_is_tabulated_again(tmp_path):
    # old: the second request (seed 7) returned the seed-0 table from the cache
    model = bl.Layered([bl.RoughDielectric(0.2, 1.5, 1.0)], [bl.Slab(1.0)], bl.Diffuse(0.5), samples=8)
    grid = TableGrid(2, 2, 2)
    calls = []

    def request(seed):
        def make():
            calls.append(seed)
            return tabulate(model, grid, 0.5, min_samples=8, max_samples=16, seed=seed, progress=False)
        return cached_table(model.to_dict(), grid, 0.5, "rgb", make, directory=tmp_path,
                            min_samples=8, max_samples=16, seed=seed)

    first, _, hit0 = request(0)
    again, _, hit1 = request(0)
    other, _, hit2 = request(7)
    assert (hit0, hit1, hit2) == (False, True, False) and calls == [0, 7]
    assert other.meta["seed"] == 7 and not np.array_equal(first.values, other.values)


def test_cache_file_holding_another_table_is_rebuilt(tmp_path, caplog):
    # old: any valid table file under the key's name was returned as the requested table
    table = valid_table(stderr=0.0)
    key = cache_key(MODEL, GRID, 0.01, "rgb")
    wrong = TableData(**{**table.__dict__, "model": {"type": "diffuse", "reflectance": 0.9}})
    write_table(tmp_path / f"{key}.exr", wrong)
    got, _, hit = cached_table(MODEL, GRID, 0.01, "rgb", lambda: table, directory=tmp_path)
    assert not hit and got.model == MODEL and "not the one requested" in caplog.text


def test_tabulate_says_when_the_target_is_not_met(tmp_path):
    # old: "from cache yes" was the only hint; no accuracy verdict at all
    model = json.dumps(bl.Layered([bl.RoughDielectric(0.2, 1.5, 1.0)], [bl.Slab(1.0, sigma_s=2.0)],
                                  bl.Diffuse(0.8), samples=8).to_dict())
    out = cli("tabulate", "--json", model, "--theta-i", "2", "--theta-o", "2", "--phi", "2", "--rel-error",
              "0.0001", "--min-samples", "16", "--max-samples", "16", "--quiet", "--cache-dir", str(tmp_path),
              "--method", "pfmc")
    assert out.returncode == 0, out.stderr
    assert "target met    NO" in out.stdout and "exceeds the target 0.0001: raise --max-samples" in out.stderr

