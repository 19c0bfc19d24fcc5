"""Measured files over HTTP (docs/service.md, docs/measured.md "Service"): uploaded by their
bytes, named in models by their SHA-256 only; the reader checks the upload; keys scope the
list; a path is still refused."""
from __future__ import annotations

import hashlib

import numpy as np
import pytest
from fastapi.testclient import TestClient

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import Measured, Merl, export_model
from bsdflab.measured.merl import DIMS, merl_bytes
from bsdflab.service import Settings, create_app
from bsdflab.service.artefact_refs import REFUSED
from bsdflab.slices import directions_from_angles

ALICE, BOB = "alice-key-0123456789", "bob-key-0123456789ab"
KEYS = {"alice": {"key": ALICE, "rate_per_s": 1000}, "bob": {"key": BOB, "rate_per_s": 1000}}
CAP = 40 << 20   # above a MERL file (35 MB), below the default, so the 413 costs little
ANGLES = {"theta_i": [0, 20, 45, 70, 30], "theta_o": [10, 30, 60, 40, 30], "phi": [0, 90, 180, 135, 180]}


def key(value: str | None) -> dict[str, str]:
    return {} if value is None else {"X-API-Key": value}


def upload(client, data: bytes, fmt: str, who: str | None = ALICE):
    return client.post("/v1/measured", params={"format": fmt}, content=data,
                       headers={"content-type": "application/octet-stream", **key(who)})


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small RGL file from the writer and a MERL file of smooth random values."""
    folder = tmp_path_factory.mktemp("measured-http")
    export_model(RoughConductor(alpha=0.2, material="Cu"), folder / "cu.bsdf", n_theta_i=4, resolution=8,
                 error_points=100)
    values = 0.01 + 0.5 * np.random.default_rng(3).random((3, *DIMS))
    (folder / "m.binary").write_bytes(merl_bytes(values))
    return folder / "cu.bsdf", folder / "m.binary"


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    settings = Settings(data_dir=(folder := tmp_path_factory.mktemp("measured-data")), cache_dir=folder / "tables",
                        executor="threads", workers=1,
                        api_keys=KEYS, limit_measured_bytes=CAP)
    with TestClient(create_app(settings)) as c:
        yield c


@pytest.mark.parametrize("fmt, reader, model_type, which",
                         [("rgl", Measured, "measured", 0), ("merl", Merl, "merl", 1)])
def test_eval_by_hash_equals_the_reader_on_the_same_file(client, files, fmt, reader, model_type, which):
    """Before: no route took a measured file (its path refused), so a client could not use one."""
    path = files[which]
    data = path.read_bytes()
    r = upload(client, data, fmt)
    assert r.status_code == 200, r.text
    answer = r.json()
    assert answer["hash"] == hashlib.sha256(data).hexdigest() and answer["format"] == fmt
    assert answer["summary"]["bytes"] == len(data) and "path" not in str(answer) and "/" not in str(answer)
    assert upload(client, data, fmt).json() == answer   # the same bytes, the same hash and record
    r = client.post("/v1/bsdf/eval", json={"model": {"type": model_type, "hash": answer["hash"]}, **ANGLES},
                    headers=key(ALICE))
    assert r.status_code == 200, r.text
    values = r.json()["values"]
    r = client.post("/v1/bsdf/lobe", json={"model": {"type": model_type, "hash": answer["hash"]}, "points": 5,
                                           "resolution": 5}, headers=key(ALICE))
    assert r.status_code == 200 and r.json()["model"] == {"type": model_type, "hash": answer["hash"]}, r.text
    wi, wo = directions_from_angles(ANGLES["theta_i"], ANGLES["theta_o"], ANGLES["phi"])
    direct = reader(path).eval(wi, wo)
    np.testing.assert_allclose(values, direct, rtol=0, atol=1e-12)
    assert np.max(direct) > 0.01   # not a vacuous comparison of zeros


def test_a_bad_upload_is_422_naming_the_field_and_stores_nothing(client, files):
    rgl = files[0].read_bytes()
    before = set(client.app.state.settings.artefact_dir.iterdir())
    for data, fmt in ((rgl[: len(rgl) // 2], "rgl"), (b"XXXX" + rgl[4:], "rgl"), (rgl, "merl"),
                      (files[1].read_bytes()[:-8], "merl")):
        r = upload(client, data, fmt)
        assert r.status_code == 422, r.text
        detail = r.json()["detail"]
        assert "the upload" in detail and str(client.app.state.settings.data_dir) not in detail
        assert "/" not in detail.replace("1/sr", ""), detail
    assert set(client.app.state.settings.artefact_dir.iterdir()) == before
    truncated = upload(client, rgl[: len(rgl) // 2], "rgl").json()["detail"]
    assert "field" in truncated or "header" in truncated, truncated


def test_over_the_cap_is_413_and_no_key_is_401(client, files):
    r = upload(client, b"\0" * (CAP + 1), "merl")
    assert r.status_code == 413 and "BSDFLAB_LIMIT_MEASURED_BYTES" in r.text
    assert upload(client, files[0].read_bytes(), "rgl", who=None).status_code == 401
    assert client.get("/v1/measured").status_code == 401
    assert upload(client, files[0].read_bytes(), "pdf").status_code == 422


def test_a_client_lists_only_its_own_uploads(client, files):
    h = upload(client, files[0].read_bytes(), "rgl").json()["hash"]
    mine = client.get("/v1/measured", headers=key(ALICE)).json()["measured"]
    assert h in [m["hash"] for m in mine]
    assert client.get("/v1/measured", headers=key(BOB)).json()["measured"] == []
    # the hash is a capability: Bob may use it once he knows it, and uploading it makes it his
    assert upload(client, files[0].read_bytes(), "rgl", who=BOB).json()["hash"] == h
    assert [m["hash"] for m in client.get("/v1/measured", headers=key(BOB)).json()["measured"]] == [h]


def test_paths_and_unknown_hashes_are_refused(client, files):
    for model_type in ("measured", "merl"):
        for model in ({"type": model_type, "path": str(files[0])}, {"type": model_type, "path": "/etc/passwd"},
                      {"type": model_type, "hash": "0" * 64, "path": str(files[0])}):
            r = client.post("/v1/bsdf/eval", json={"model": model, **ANGLES}, headers=key(ALICE))
            assert r.status_code == 422 and r.json()["detail"] == REFUSED, r.text
        r = client.post("/v1/bsdf/eval", json={"model": {"type": model_type, "hash": "0" * 64}, **ANGLES},
                        headers=key(ALICE))
        assert r.status_code == 422 and r.json()["detail"] == f"no {model_type} {'0' * 64} in this server's " \
                                                              "store (GET /v1/measured)"
    # an RGL upload is not a MERL file: the type must match the format
    h = upload(client, files[0].read_bytes(), "rgl").json()["hash"]
    r = client.post("/v1/bsdf/eval", json={"model": {"type": "merl", "hash": h}, **ANGLES}, headers=key(ALICE))
    assert r.status_code == 422 and "no merl" in r.json()["detail"]


def test_a_table_of_an_upload_shows_it_by_hash(client, files, tmp_path):
    """Before: the table's metadata named the uploaded file's server path."""
    export_model(RoughConductor(alpha=0.2, material="Cu"), tmp_path / "s.bsdf", wavelengths=[450.0, 550.0, 650.0],
                 n_theta_i=4, resolution=8, error_points=100)
    h = upload(client, (tmp_path / "s.bsdf").read_bytes(), "rgl").json()["hash"]
    job = client.post("/v1/tables", json={"model": {"type": "measured", "hash": h},
                                          "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}},
                      headers=key(ALICE)).json()
    while job["state"] not in ("done", "failed"):
        job = client.get(f"/v1/jobs/{job['id']}", headers=key(ALICE)).json()
    assert job["state"] == "done", job
    r = client.get(f"/v1/tables/{job['hash']}", headers=key(ALICE))
    assert r.json()["model"] == {"type": "measured", "hash": h}
    data_dir = str(client.app.state.settings.data_dir)
    assert data_dir not in r.text and data_dir not in client.get("/v1/tables", headers=key(ALICE)).text
