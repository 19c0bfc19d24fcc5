"""/v1/tables (and the render limits) through TestClient: a table job, the cache, limits,
the queue, missing things."""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab import Diffuse
from bsdflab.tables import TableGrid, cache_key, read_table, tabulate
from support.service_client import LONG_TABLE, TINY_TABLE, detail, make_client, wait_job


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("tables")) as c:
        yield c


def test_table_job_then_cached(client):
    r = client.post("/v1/tables", json=TINY_TABLE)
    assert r.status_code == 202, r.text
    job = wait_job(client, r.json()["id"])
    assert job["state"] == "done" and job["progress"] == 1.0
    key = cache_key(Diffuse(0.5).to_dict(), TableGrid(2, 4, 3), 0.01, ("R", "G", "B"))
    assert job["hash"] == key
    again = client.post("/v1/tables", json=TINY_TABLE)
    assert again.status_code == 200 and again.json()["hash"] == key
    info = client.get(f"/v1/tables/{key}").json()
    assert info["grid"]["n_theta_o"] == 4 and set(info["error"]) == {"rms", "p95", "max", "cells"}
    assert key in [t["hash"] for t in client.get("/v1/tables").json()["tables"]]
    download = client.get(f"/v1/tables/{key}/file")
    assert download.status_code == 200 and download.headers["content-type"] == "image/x-exr"
    path = client.app.state.settings.artefact_dir / "download-check.exr"
    path.write_bytes(download.content)
    direct = tabulate(Diffuse(0.5), TableGrid(2, 4, 3), progress=False)
    np.testing.assert_array_equal(read_table(path).values, direct.values)
    path.unlink()


def test_limits_queue_and_missing_things(client):
    r = client.post("/v1/tables", json={**TINY_TABLE, "grid": {"n_theta_i": 64, "n_theta_o": 64, "n_phi": 64}})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_TABLE_CELLS" in detail(r)
    r = client.post("/v1/renders", json={"scene": "sphere", "width": 4000, "height": 2000, "spp": 1})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_RENDER_PIXELS" in detail(r)
    r = client.post("/v1/renders", json={"scene": "sphere", "width": 1000, "height": 1000, "spp": 1024})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_RENDER_SAMPLES" in detail(r)
    r = client.post("/v1/renders", json={"scene": "sphere", "options": {"colour": "red"}})
    assert r.status_code == 422 and "colour" in detail(r)
    # distinct keys (the table cache's key holds the target error, not yet the seed)
    ids = [client.post("/v1/tables", json={**LONG_TABLE, "rel_error": e}).json()["id"] for e in (0.1, 0.2, 0.3)]
    assert len(set(ids)) == 3
    full = client.post("/v1/tables", json={**LONG_TABLE, "rel_error": 0.4})
    assert full.status_code == 429 and "BSDFLAB_LIMIT_QUEUE" in detail(full)
    for job_id in ids:
        client.delete(f"/v1/jobs/{job_id}")
    for job_id in ids:
        assert wait_job(client, job_id)["state"] == "cancelled"
    missing = "0" * 64
    assert client.get(f"/v1/tables/{missing}").status_code == 404
    assert client.get(f"/v1/tables/{missing}/file").status_code == 404
    assert client.get(f"/v1/renders/{missing}").status_code == 404
    assert client.get(f"/v1/renders/{missing}/image.png").status_code == 404
    assert client.get(f"/v1/jobs/{'0' * 32}").status_code == 404
    assert client.get("/v1/jobs/..%2F..%2Fetc").status_code in (404, 422)
    assert client.get("/v1/tables/not-a-hash").status_code == 422


def test_adding_doubling_table_job(client):
    """method "adding-doubling": a job under its own key (not the PFMC one), its method
    and error bound in the table's info; a model it cannot solve is refused at submission."""
    from bsdflab.presets import preset

    body = {"preset": "xenopeltis", "grid": {"n_theta_i": 2, "n_theta_o": 3, "n_phi": 2},
            "wavelengths": [450.0, 550.0, 650.0], "method": "adding-doubling"}
    r = client.post("/v1/tables", json=body)
    assert r.status_code == 202, r.text
    job = wait_job(client, r.json()["id"])
    assert job["state"] == "done", job
    grid, wl = TableGrid(2, 3, 2), [450.0, 550.0, 650.0]
    d = preset("xenopeltis").to_dict()
    assert job["hash"] == cache_key(d, grid, 0.01, wl, method="adding-doubling") != cache_key(d, grid, 0.01, wl)
    info = client.get(f"/v1/tables/{job['hash']}").json()
    assert info["meta"]["method"] == "adding-doubling" and info["meta"]["error_bound_max_rel"] < 0.01
    assert client.post("/v1/tables", json=body).status_code == 200          # cached
    r = client.post("/v1/tables", json={**body, "preset": "xenopeltis-diffuse"})
    assert r.status_code == 422 and "tabulates Layered models" in detail(r)
    r = client.post("/v1/tables", json={**body, "method": "exact"})
    assert r.status_code == 422 and "method" in detail(r)
