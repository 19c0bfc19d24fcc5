"""Tables by adding-doubling in the table cache, the CLI and through runners: the method
is part of the key (and a PFMC key is the one it was before methods existed), a table
made by the other method is refused under a key, the CLI caches both, and a table split
over a runner's workers by thickness node equals the in-process one bit for bit."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from bsdflab.presets import preset
from bsdflab.tables import TableGrid, cache_key, cached_table, read_table, tabulate
from bsdflab.tables.cache import request_dict
from bsdflab.util.runners import LocalRunner

WL = [450.0, 550.0, 650.0]
GRID = TableGrid(2, 3, 2, thickness_nm=(360.0, 400.0, 440.0))
BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main"]


def two_workers() -> LocalRunner:
    """The local runner reporting two workers, so the driver plans two units (an instance
    attribute: a subclass would register itself in the runner registry under "local")."""
    runner = LocalRunner()
    runner.workers = lambda: 2
    return runner


@pytest.fixture(scope="module")
def model():
    return preset("xenopeltis")


@pytest.fixture(scope="module")
def ad_table(model):
    return tabulate(model, GRID, wavelengths=WL, method="adding-doubling", progress=False)


def test_01_method_in_the_key_pfmc_keys_unchanged(model):
    d = model.to_dict()
    pfmc = request_dict(d, GRID, 0.01, WL)
    assert "method" not in pfmc and "solver" not in pfmc        # keys cached before methods stay valid
    ad = request_dict(d, GRID, 0.01, WL, method="adding-doubling")
    assert ad["method"] == "adding-doubling" and ad["solver"]["nodes"] == 16
    assert "seed" not in ad and "estimator_version" not in ad   # walks do not make this table
    assert cache_key(d, GRID, 0.01, WL) == cache_key(d, GRID, 0.01, WL, method="pfmc")
    assert cache_key(d, GRID, 0.01, WL) != cache_key(d, GRID, 0.01, WL, method="adding-doubling")
    # the seed does not change an adding-doubling key
    assert cache_key(d, GRID, 0.01, WL, seed=1, method="adding-doubling") == \
        cache_key(d, GRID, 0.01, WL, seed=2, method="adding-doubling")
    with pytest.raises(ValueError, match="method must be one of"):
        cache_key(d, GRID, 0.01, WL, method="exact")


def test_02_cached_then_hit_and_the_other_method_refused(model, ad_table, tmp_path):
    d = model.to_dict()
    calls = []

    def make():
        calls.append(1)
        return ad_table

    t1, path, hit = cached_table(d, GRID, 0.01, WL, make, directory=tmp_path, method="adding-doubling")
    assert not hit and path.is_file() and calls == [1]
    t2, path2, hit2 = cached_table(d, GRID, 0.01, WL, make, directory=tmp_path, method="adding-doubling")
    assert hit2 and path2 == path and calls == [1]
    np.testing.assert_array_equal(t2.values, ad_table.values)
    # an adding-doubling table offered for a PFMC request is refused, not cached
    with pytest.raises(ValueError, match="different method"):
        cached_table(d, GRID, 0.01, WL, make, directory=tmp_path / "pfmc")


def test_03_target_met_follows_the_error_bound(ad_table):
    # "target met": the 95th percentile of the cells' relative bound (bsdflab.tables.summary)
    accuracy = ad_table.accuracy()
    assert accuracy["kind"] == "deterministic bound" and accuracy["p95"] == ad_table.meta["rel_error_p95"]
    assert accuracy["target_met"] == (ad_table.meta["rel_error_p95"] <= 0.01)
    assert accuracy["target_met"] and accuracy["max"] == ad_table.meta["error_bound_max_rel"]
    strict = type(ad_table)(**{**ad_table.__dict__, "rel_error_target": 1e-9})
    assert not strict.accuracy()["target_met"]


def test_04_thickness_nodes_split_over_workers_equal_the_local_table(model, ad_table):
    remote = tabulate(model, GRID, wavelengths=WL, method="adding-doubling", progress=False, runner=two_workers())
    assert remote.meta["units"] == 2
    for name in ("values", "stderr", "samples"):
        assert np.array_equal(getattr(ad_table, name), getattr(remote, name)), name
    for key in ("error_bound_max_rel", "rel_error_rms", "rel_error_p95"):
        assert remote.meta[key] == ad_table.meta[key], key
    no_nodes = TableGrid(2, 3, 2)
    one = tabulate(model, no_nodes, wavelengths=WL, method="adding-doubling", progress=False, runner=two_workers())
    assert one.meta["units"] == 1 and one.values.shape[1] == 1


def test_05_cli_method_writes_and_caches(tmp_path, capsys, monkeypatch):
    """The first run is the program (a child process); the cache hit and the refusal call its
    main in this process (support.cli.cli_in_process). Mutation: cached_table's lookup
    skipped (always a miss, tables/cache.py) fails it."""
    from support.cli import cli_in_process

    out = tmp_path / "ad.exr"
    args = ["tabulate", "--preset", "xenopeltis", "--method", "adding-doubling", "--theta-i", "2",
            "--theta-o", "3", "--phi", "2", "--wavelengths", *map(str, WL), "--cache-dir", str(tmp_path / "c"),
            "--quiet", "--out", str(out)]
    first = subprocess.run([*BSDFLAB, *args], capture_output=True, text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    assert "from cache    no" in first.stdout and "relative deterministic bound" in first.stdout
    table = read_table(out)
    assert table.meta["method"] == "adding-doubling"
    second = cli_in_process(capsys, monkeypatch, *args)
    assert second.returncode == 0 and "from cache    yes" in second.stdout, second.stdout + second.stderr
    bad = cli_in_process(capsys, monkeypatch, "tabulate", "--preset", "xenopeltis-diffuse", "--method",
                         "adding-doubling", "--out", str(tmp_path / "x.exr"), "--quiet")
    assert bad.returncode == 2 and "tabulates Layered models" in bad.stderr
    assert not (tmp_path / "x.exr").exists()
