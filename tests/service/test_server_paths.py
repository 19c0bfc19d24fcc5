"""No server paths over HTTP (docs/service.md, "Security"): every path-bearing field gets
one and the same refusal, whatever it names, and a table is named by its content hash."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest
from fastapi.testclient import TestClient

from bsdflab import Diffuse
from bsdflab.service import Settings, create_app
from bsdflab.service.artefact_refs import REFUSED
from bsdflab.slices import directions_from_angles
from bsdflab.tables import TableBSDF, TableGrid, tabulate, write_table

ANGLES = {"theta_i": [10, 40], "theta_o": [20, 60]}


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """A client, a real table file outside the store, and the hash of one inside it."""
    folder = tmp_path_factory.mktemp("paths")
    outside = folder / "outside.exr"
    write_table(outside, tabulate(Diffuse(0.3), TableGrid(2, 4, 3), progress=False))
    settings = Settings(data_dir=folder / "data", cache_dir=folder / "tables",
                        executor="threads", workers=1, progress_interval_s=0.05)
    with TestClient(create_app(settings)) as client:
        r = client.post("/v1/tables", json={"model": {"type": "diffuse", "reflectance": 0.5},
                                            "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}})
        job = r.json()
        while job["state"] not in ("done", "failed"):
            job = client.get(f"/v1/jobs/{job['id']}").json()
        assert job["state"] == "done", job
        yield client, outside, job["hash"]


def probes(outside) -> list:
    """Paths a prober would try: a real table, a folder, a missing file, a system file,
    traversal, encodings, a file URL, a path inside a list."""
    return [str(outside), str(outside.parent), str(outside.parent / "missing.exr"), "/etc/passwd",
            "../../../../etc/passwd", "%2Fetc%2Fpasswd", "file:///etc/passwd", "\\\\server\\share\\t.exr",
            os.fspath(outside).encode().hex(), ["/etc/passwd"], {"path": "/etc/passwd"}]


def test_every_path_field_gets_one_refusal(served):
    """Before: a table path opened any file, and the messages said whether it existed, was
    a folder or not an EXR (the real table evaluated with 200)."""
    client, outside, _ = served
    answers = set()
    for probe in probes(outside):
        bodies = [
            ("/v1/bsdf/eval", {"model": {"type": "table", "path": probe}, **ANGLES}),
            ("/v1/bsdf/eval", {"model": {"type": "table", "table": probe}, **ANGLES}),
            ("/v1/bsdf/eval", {"model": {"type": "table", "hash": "0" * 64, "path": probe}, **ANGLES}),
            ("/v1/bsdf/eval", {"preset": "xenopeltis", "overrides": {"path": probe}, **ANGLES}),
            ("/v1/bsdf/lobe", {"model": {"type": "layered", "layers": [{"type": "table", "path": probe}]}}),
            ("/v1/bsdf/lobe.png", {"model": {"type": "table", "path": probe}}),
            ("/v1/tables", {"model": {"type": "table", "path": probe}}),
            ("/v1/renders", {"scene": "sphere", "options": {"mesh": probe}}),
            ("/v1/renders", {"scene": "sphere", "options": {"environment_map": probe}}),
            ("/v1/renders", {"scene": "sphere", "options": {"scene_file": probe}}),
        ]
        for route, body in bodies:
            r = client.post(route, json=body)
            assert r.status_code == 422, (route, body, r.text)
            answers.add(r.json()["detail"])
        r = client.get("/v1/bsdf/lobe.png", params={"model": json.dumps({"type": "table", "path": probe})})
        assert r.status_code == 422
        answers.add(r.json()["detail"])
    assert answers == {REFUSED}


def test_a_table_is_named_by_its_hash(served):
    client, _, key = served
    r = client.post("/v1/bsdf/eval", json={"model": {"type": "table", "hash": key}, **ANGLES})
    assert r.status_code == 200, r.text
    wi, wo = directions_from_angles(ANGLES["theta_i"], ANGLES["theta_o"], [180])
    direct = TableBSDF(path=str(client.app.state.jobs.table_dir / f"{key}.exr")).eval(wi, wo)
    np.testing.assert_array_equal(r.json()["values"], direct)
    lobe = client.post("/v1/bsdf/lobe", json={"model": {"type": "table", "hash": key}, "points": 5,
                                              "resolution": 5}).json()
    assert lobe["model"] == {"type": "table", "hash": key}          # the answer names no path either
    assert str(client.app.state.settings.data_dir) not in json.dumps(lobe)
    for bad in ("0" * 64, key.upper(), key[:-1], "../" + key, key + "\x00"):
        r = client.post("/v1/bsdf/eval", json={"model": {"type": "table", "hash": bad}, **ANGLES})
        assert r.status_code == 422 and "/" not in r.json()["detail"].replace("/v1/tables", ""), r.text


def test_hostile_nesting_is_a_clean_422(served):
    """The walk that looks for paths must not be a way to exhaust the stack (a 500)."""
    client, _, _ = served
    deep: object = 0.5
    for _ in range(900):
        deep = [deep]
    r = client.post("/v1/bsdf/eval", json={"model": {"type": "diffuse", "reflectance": deep}, **ANGLES})
    assert r.status_code == 422 and "nest" in r.text
