"""Words that match the numbers (issue 32, item 6): "target met" is defined once
(bsdflab/tables/summary.py: the 95th percentile of the cells' relative error <= target,
the max beside it), and `bsdflab tabulate`, `table info` and `table plot` say it in the
file's own figures and the right kind of error."""
from __future__ import annotations

import os
import re
import shlex
import subprocess
from pathlib import Path

import pytest

from bsdflab.tables import read_table
from bsdflab.tables.summary import relative_error_summary
from support.cli import BSDFLAB, cli_in_process

ROOT = Path(__file__).resolve().parents[2]
SMALL = ["--theta-i", "2", "--theta-o", "3", "--phi", "2", "--wavelengths", "450", "550", "650", "--quiet"]


def cli(*args, cache: Path):
    return subprocess.run([*BSDFLAB, *map(str, args)], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "BSDFLAB_CACHE_DIR": str(cache)})


def here(capsys, monkeypatch, *args, cache: Path):
    """``cli`` in this process (support.cli.cli_in_process): the tables are made by the
    program itself (the fixtures' and test_04's children), info and plot are read here."""
    return cli_in_process(capsys, monkeypatch, *args, env={"BSDFLAB_CACHE_DIR": cache})


def achieved_p95(text: str) -> str:
    return re.search(r"^achieved\s+95th pct (\S+)", text, re.M).group(1)


@pytest.fixture(scope="module")
def pfmc_file(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pfmc")
    out = tmp / "p.exr"
    r = cli("tabulate", "--preset", "xenopeltis", "--method", "pfmc", "--rel-error", "0.1", "--min-samples", "32",
            "--max-samples", "256", *SMALL, "--out", out, cache=tmp / "c")
    assert r.returncode == 0, r.stderr
    return out, r


@pytest.fixture(scope="module")
def ad_file(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ad")
    out = tmp / "a.exr"
    r = cli("tabulate", "--preset", "xenopeltis", *SMALL, "--out", out, cache=tmp / "c")
    assert r.returncode == 0, r.stderr
    return out, r


def test_01_pfmc_info_shows_the_files_p95_and_the_verdict_follows_it(pfmc_file, tmp_path, capsys, monkeypatch):
    """`table info` and `tabulate` print the p95 the file's meta records (old: info
    recomputed it from the per-channel errors, 0.05118 against the meta's 0.0494). Power:
    the per-channel recomputation differs from the meta here, so the old code fails.
    Mutation: summary.achieved ignoring the meta's figures fails it."""
    out, tab = pfmc_file
    table = read_table(out)
    p95 = table.meta["rel_error_p95"]
    assert f"{relative_error_summary(table)['p95']:.4g}" != f"{p95:.4g}"
    info = here(capsys, monkeypatch, "table", "info", out, cache=tmp_path)
    assert info.returncode == 0, info.stderr
    assert achieved_p95(info.stdout) == achieved_p95(tab.stdout) == f"{p95:.4g}"
    met = p95 <= 0.1
    verdict = f"target met    {'yes' if met else 'NO'}: 95th pct {p95:.4g} {'<=' if met else '>'} 0.1 (max "
    assert verdict in tab.stdout
    assert "relative standard error of luminance" in info.stdout and "walks per cell" in info.stdout


def test_02_ad_info_calls_the_bound_a_bound(ad_file, tmp_path, capsys, monkeypatch):
    """An adding-doubling table: a deterministic bound, the solver's settings, no walk
    counts (old: 'samples min 1', 'meta max_samples 16777216', 'relative standard error').
    Mutation: summary.error_kind not calling an adding-doubling table's error a bound fails it."""
    out, tab = ad_file
    info = here(capsys, monkeypatch, "table", "info", out, cache=tmp_path)
    assert info.returncode == 0, info.stderr
    text = info.stdout
    assert "relative deterministic bound of luminance" in text and "16 nodes per panel" in text
    for wrong in ("standard error", "walks per cell", "max_samples", "min_samples", "samples min"):
        assert wrong not in text, wrong
    assert achieved_p95(text) == f"{read_table(out).meta['rel_error_p95']:.4g}"
    assert "relative deterministic bound" in tab.stdout and "standard error" not in tab.stdout


def test_03_plot_labels_the_bands_and_the_peak_added_at_lookup(ad_file, pfmc_file, tmp_path, capsys, monkeypatch):
    """Mutation: plots/table.py labelling the bound's bands as standard errors fails it."""
    ad = here(capsys, monkeypatch, "table", "plot", ad_file[0], "--out", tmp_path / "a.png", cache=tmp_path)
    assert ad.returncode == 0, ad.stderr
    assert "bands = +- the solver's deterministic bound" in ad.stdout and "standard error" not in ad.stdout
    assert "specular peak included) is added exactly at lookup" in ad.stdout
    pf = here(capsys, monkeypatch, "table", "plot", pfmc_file[0], "--out", tmp_path / "p.png", cache=tmp_path)
    assert pf.returncode == 0 and "bands = +-2 standard errors" in pf.stdout


def test_04_the_solvers_accuracy_options_reach_the_table(tmp_path):
    """--nodes is the solver's (recorded in meta, its own cache key); a target the bound
    misses names --nodes, which the command now has (old: 'more nodes', no such option)."""
    out = tmp_path / "n.exr"
    r = cli("tabulate", "--preset", "xenopeltis", *SMALL, "--nodes", "20", "--rel-error", "1e-6", "--out", out,
            cache=tmp_path / "c")
    assert r.returncode == 0, r.stderr
    assert read_table(out).meta["solver"]["nodes"] == 20
    assert "target met    NO" in r.stdout and "raise --nodes (this table used 20) or --orders" in r.stderr
    bad = cli("tabulate", "--preset", "xenopeltis-diffuse", *SMALL, "--nodes", "20", "--out", tmp_path / "x.exr",
              cache=tmp_path / "c")
    assert bad.returncode == 2 and "nodes and orders are the adding-doubling solver's" in bad.stderr


def test_05_the_readmes_adding_doubling_command_meets_its_target(tmp_path):
    line = next(x for x in (ROOT / "README.md").read_text().splitlines()
                if x.startswith("bsdflab tabulate") and "adding-doubling" in x)
    args = shlex.split(line.split("#")[0])[1:]
    args[args.index("--out") + 1] = str(tmp_path / "x_ad.exr")
    r = cli(*args, cache=tmp_path / "c")
    assert r.returncode == 0, r.stderr
    assert "warning" not in r.stderr and "target met    yes" in r.stdout
