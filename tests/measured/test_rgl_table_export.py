"""`bsdflab table export T.exr --format rgl`: a table becomes an RGL file that Mitsuba 3's
``measured`` plugin reads, and that answers like the table within the bound the writer
reports (fresh random pairs, another seed than the writer's)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from bsdflab.bsdfs import RoughConductor
from bsdflab.cli.main import main
from bsdflab.measured import Measured
from bsdflab.measured.rgl import random_pairs
from bsdflab.reference.mitsuba_calls import query
from bsdflab.tables import TableBSDF, TableGrid, tabulate, write_table

pytestmark = pytest.mark.mitsuba


@pytest.fixture(scope="module")
def table_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("table") / "copper.exr"
    table = tabulate(RoughConductor(alpha=0.3, material="Cu"), TableGrid(n_theta_i=8, n_theta_o=16, n_phi=9),
                     rel_error=0.05, progress=False)
    write_table(path, table)
    return path


def test_cli_export_and_mitsuba_agreement(table_path, tmp_path, capsys):
    out = tmp_path / "copper.bsdf"
    assert main(["table", "export", str(table_path), "--format", "rgl", "--out", str(out),
                 "--theta-i", "8", "--resolution", "24"]) == 0
    printed = capsys.readouterr().out
    assert "resampling error" in printed
    m = Measured(out)
    header = json.loads(m.data.description)
    assert header["source"]["kind"] == "bsdflab table" and header["source"]["table_content_hash"]
    bound = header["error"]["bound"]
    rng = np.random.default_rng(99)
    wi, wo = random_pairs(m.reference, 2000, rng)
    wi, wo = wi.astype(np.float32).astype(float), wo.astype(np.float32).astype(float)
    keep = (wi[:, 2] > np.sin(np.radians(0.5))) & (wo[:, 2] > np.sin(np.radians(0.5)))
    wi, wo = wi[keep], wo[keep]
    source = TableBSDF(table_path).eval(wi, wo)
    theirs = query({"type": "measured", "filename": str(out)}, wi, wo, rng.random(len(wi)), rng.random((len(wi), 2)))
    ours = m.eval(wi, wo)
    assert np.abs(ours - source).max() <= bound
    assert np.abs(theirs.eval - source).max() <= bound * (1 + 1e-4)
    assert np.abs(theirs.eval - ours).max() <= 1e-4 * np.abs(ours).max()
