"""The HTTP API through TestClient, router by router: answers equal the Python API's, and
everything a client gets wrong is a 4xx naming the problem.

Jobs run on the in-process thread executor here (the worker-process executor and a real
server are tested in test_service_live.py)."""
from __future__ import annotations

import json
import time

import numpy as np
import pytest
from fastapi.testclient import TestClient

from bsdflab import Diffuse, presets
from bsdflab.slices import directions_from_angles, evaluate, hemisphere, plane_of_incidence
from bsdflab.optics import film_reflectance, film_transmittance
from bsdflab.plots.film_colour import spectral_rgb
from bsdflab.scenes import SCENES
from bsdflab.service import Settings, create_app
from bsdflab.tables import TableGrid, cache_key, read_table, tabulate

DIFFUSE = {"type": "diffuse", "reflectance": 0.5}
TINY_TABLE = {"model": DIFFUSE, "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}}
# a layered table long enough to still be running when the test looks (many cells, cancelled)
LONG_TABLE = {"preset": "xenopeltis-thin-film", "grid": {"n_theta_i": 12, "n_theta_o": 24, "n_phi": 13},
              "min_samples": 4096, "max_samples": 4096}


def make_client(tmp_path, **settings) -> TestClient:
    defaults = {"data_dir": tmp_path, "executor": "threads", "workers": 1, "limit_directions": 500,
                "limit_body_bytes": 64 << 10, "limit_queue": 3, "limit_table_cells": 50_000,
                "progress_interval_s": 0.05}
    return TestClient(create_app(Settings(**{**defaults, **settings})))


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("service")) as c:
        yield c


def detail(response) -> str:
    return json.dumps(response.json()["detail"])


def wait_job(client, job_id, states=("done", "failed", "cancelled"), timeout=120):
    end = time.monotonic() + timeout
    while True:
        job = client.get(f"/v1/jobs/{job_id}").json()
        if job["state"] in states:
            return job
        assert time.monotonic() < end, job
        time.sleep(0.05)


# -- /v1/bsdf ------------------------------------------------------------------------------
def test_eval_diffuse_is_the_closed_form(client):
    """Lambert: f cos = R cos(theta_o) / pi; angles and vectors give the same pairs."""
    body = {"model": DIFFUSE, "theta_i": [0, 30, 60], "theta_o": [10, 45, 80], "phi": [180]}
    r = client.post("/v1/bsdf/eval", json=body)
    assert r.status_code == 200, r.text
    out = r.json()
    expected = 0.5 * np.cos(np.radians([10, 45, 80])) / np.pi
    np.testing.assert_allclose(np.asarray(out["values"]), np.repeat(expected[:, None], 3, axis=1), rtol=1e-12)
    assert out["stderr"] is None and not out["stochastic"] and out["channels"] == ["R", "G", "B"]
    wi, wo = directions_from_angles([0, 30, 60], [10, 45, 80], [180])
    by_vector = client.post("/v1/bsdf/eval", json={"model": DIFFUSE, "wi": wi.tolist(), "wo": wo.tolist()}).json()
    np.testing.assert_array_equal(by_vector["values"], out["values"])


def test_eval_layered_equals_the_python_api_and_repeats(client):
    body = {"preset": "xenopeltis", "overrides": {"film_thickness_nm": 500.0}, "theta_i": [20],
            "theta_o": [20, 40], "samples": 64, "seed": 3, "wavelengths": [450, 550, 650]}
    first, second = (client.post("/v1/bsdf/eval", json=body).json() for _ in range(2))
    assert first == second and first["stochastic"] and first["channels"] == ["450", "550", "650"]
    wi, wo = directions_from_angles([20], [20, 40], [180])
    direct = evaluate(presets.xenopeltis(film_thickness_nm=500.0), wi, wo, [450, 550, 650], 64, 3)
    np.testing.assert_array_equal(first["values"], direct.values)
    np.testing.assert_array_equal(first["stderr"], direct.stderr)


@pytest.mark.parametrize("body, status, words", [
    ({"preset": "nope", "theta_i": [0], "theta_o": [0]}, 422, "unknown preset 'nope'"),
    ({"model": DIFFUSE, "preset": "xenopeltis", "theta_i": [0], "theta_o": [0]}, 422, "exactly one"),
    ({"model": {"type": "diffuse", "reflectance": 2}, "theta_i": [0], "theta_o": [0]}, 422, "reflectance"),
    ({"model": DIFFUSE, "wi": [[0, 0, 2]], "wo": [[0, 0, 1]]}, 422, "wi must be unit vectors"),
    ({"model": DIFFUSE, "theta_i": [95], "theta_o": [0]}, 422, "theta_i must be <= 90"),
    ({"model": DIFFUSE, "wi": [[0, 0, 1]], "theta_o": [0]}, 422, "either as vectors"),
    ({"model": DIFFUSE, "theta_i": [0] * 501, "theta_o": [0]}, 422, "BSDFLAB_LIMIT_DIRECTIONS"),
    ({"model": DIFFUSE, "theta_i": [0], "theta_o": [0], "colour": 1}, 422, "colour"),
    ({"preset": "xenopeltis", "overrides": {"thickness": 1}, "theta_i": [0], "theta_o": [0]}, 422, "thickness"),
    ({"preset": "xenopeltis", "theta_i": [0], "theta_o": [0], "samples": 100_000}, 422, "BSDFLAB_LIMIT_SAMPLES"),
    ({"model": DIFFUSE, "theta_i": [0], "theta_o": [0], "seed": -1}, 422, "seed"),
])
def test_eval_errors_are_422_with_a_message(client, body, status, words):
    r = client.post("/v1/bsdf/eval", json=body)
    assert r.status_code == status and words in detail(r), r.text


def test_malformed_and_oversized_bodies(client):
    r = client.post("/v1/bsdf/eval", content=b"{not json", headers={"content-type": "application/json"})
    assert r.status_code == 422
    r = client.post("/v1/bsdf/eval", content=b"[" + b"0," * 40_000 + b"0]", headers={"content-type": "application/json"})
    assert r.status_code == 413 and "BSDFLAB_LIMIT_BODY_BYTES" in r.text


def test_lobe_views_equal_the_python_api(client):
    r = client.post("/v1/bsdf/lobe", json={"model": DIFFUSE, "theta_i": 30, "points": 7, "resolution": 9})
    assert r.status_code == 200, r.text
    out = r.json()
    angles, v = plane_of_incidence(presets.xenopeltis_diffuse(base_albedo=0.5), 30, 7)
    np.testing.assert_array_equal(out["plane"]["angle_deg"], angles)
    np.testing.assert_allclose(np.asarray(out["plane"]["values"])[:, 0], 0.5 * np.cos(np.radians(angles)) / np.pi,
                               rtol=1e-12, atol=1e-15)
    x, inside, hv = hemisphere(presets.xenopeltis_diffuse(base_albedo=0.5), 30, 9)
    lum = np.asarray([[np.nan if c is None else c for c in row] for row in out["hemisphere"]["luminance"]])
    assert np.array_equal(~np.isnan(lum), inside)
    np.testing.assert_allclose(lum[inside], hv.values @ [0.2126, 0.7152, 0.0722], rtol=1e-12)
    assert not out["stochastic"] and out["hemisphere"]["luminance_stderr"] is None


def test_lobe_png_and_its_errors(client):
    r = client.get("/v1/bsdf/lobe.png", params={"model": json.dumps(DIFFUSE), "theta_i": 20, "samples": 2000})
    assert r.status_code == 200 and r.content[:8] == b"\x89PNG\r\n\x1a\n"
    assert client.get("/v1/bsdf/lobe.png", params={"model": "{oops"}).status_code == 422
    r = client.post("/v1/bsdf/lobe.png", json={"model": DIFFUSE, "theta_i": 90})
    assert r.status_code == 422 and "theta_i" in detail(r)
    r = client.post("/v1/bsdf/lobe", json={"model": DIFFUSE, "points": 10_000})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_LOBE_RESOLUTION" in detail(r)


# -- /v1/thinfilm ----------------------------------------------------------------------------
def test_thinfilm_spectrum_equals_the_optics(client):
    body = {"film_ior": 1.6, "thickness_nm": 300, "angles": [0, 40, 70], "wavelengths": [400, 500, 600, 700]}
    out = client.post("/v1/thinfilm/spectrum", json=body).json()
    film = (1.000277, 1.6, 300.0, 1.5515)
    theta = np.radians([0, 40, 70])[:, None]
    np.testing.assert_allclose(out["reflectance"], film_reflectance(film, np.array([400, 500, 600, 700.0]), theta),
                               rtol=1e-12)
    np.testing.assert_allclose(out["transmittance"], film_transmittance(film, np.array([400, 500, 600, 700.0]), theta),
                               rtol=1e-12)
    np.testing.assert_allclose(out["rgb"], spectral_rgb(film, np.radians([0, 40, 70])), rtol=1e-12)
    assert all(len(c) == 7 and c[0] == "#" for c in out["srgb"])
    r = client.post("/v1/thinfilm/spectrum", json={"angles": [100]})
    assert r.status_code == 422 and "angles" in detail(r)
    assert client.post("/v1/thinfilm/spectrum", json={"film_ior": -1}).status_code == 422
    # found by the long schemathesis run: a tiny index gave NaN spectra (a 200 with nulls)
    r = client.post("/v1/thinfilm/spectrum", json={"film_ior": 2.632460067801165e-162})
    assert r.status_code == 422 and "film_ior" in detail(r)


# -- catalogues and meta ---------------------------------------------------------------------
def test_presets_scenes_version(client):
    listed = client.get("/v1/presets").json()
    assert [p["name"] for p in listed] == list(presets.PRESETS)
    assert listed[0]["model"] == presets.xenopeltis().to_dict()
    assert listed[0]["parameters"]["film_thickness_nm"] == presets.FILM_THICKNESS_NM
    assert [s["name"] for s in client.get("/v1/scenes").json()] == list(SCENES)
    version = client.get("/v1/version").json()
    assert version["bsdflab"] and version["limits"]["directions"] == 500 and not version["api_key_required"]
    assert client.get("/healthz").json() == {"status": "ok"}
    assert client.get("/docs").status_code == 200 and "/v1/tables" in client.get("/openapi.json").json()["paths"]


def test_page_and_plotly_are_served(client):
    page = client.get("/")
    assert page.status_code == 200 and "/vendor/plotly.min.js" in page.text
    js = client.get("/vendor/plotly.min.js")
    assert js.status_code == 200 and len(js.content) > 1_000_000
    assert client.get("/static/app.js").status_code == 200


# -- /v1/tables and jobs -------------------------------------------------------------------
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


def test_identical_requests_share_one_job_and_cancel(client):
    first = client.post("/v1/tables", json=LONG_TABLE)
    second = client.post("/v1/tables", json=LONG_TABLE)
    assert first.status_code == second.status_code == 202
    assert first.json()["id"] == second.json()["id"]
    job_id = first.json()["id"]
    wait_job(client, job_id, states=("running",))
    with client.stream("GET", f"/v1/jobs/{job_id}/events") as events:
        cancelled = client.delete(f"/v1/jobs/{job_id}")
        assert cancelled.status_code == 200 and cancelled.json()["cancel_requested"]
        lines = [line for line in events.iter_lines() if line.startswith("event:")]
    assert lines[-1] == "event: cancelled" and "event: progress" in lines
    assert wait_job(client, job_id)["state"] == "cancelled"
    assert client.delete(f"/v1/jobs/{job_id}").status_code == 200          # already cancelled
    done = next(j for j in client.get("/v1/jobs", params={"state": "done"}).json()["jobs"])
    assert client.delete(f"/v1/jobs/{done['id']}").status_code == 409


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


def test_api_key_guards_work_and_deletes(tmp_path):
    with make_client(tmp_path, api_key="s3cret") as c:
        body = {"model": DIFFUSE, "theta_i": [0], "theta_o": [0]}
        assert c.post("/v1/bsdf/eval", json=body).status_code == 401
        assert c.post("/v1/bsdf/eval", json=body, headers={"X-API-Key": "wrong"}).status_code == 401
        assert c.post("/v1/bsdf/eval", json=body, headers={"X-API-Key": "s3cret"}).status_code == 200
        assert c.post("/v1/bsdf/eval", json=body, headers={"Authorization": "Bearer s3cret"}).status_code == 200
        assert c.post("/v1/tables", json=TINY_TABLE).status_code == 401
        assert c.delete(f"/v1/jobs/{'0' * 32}").status_code == 401
        assert c.get("/v1/presets").status_code == 401 and c.get("/healthz").status_code == 200
        assert c.get("/v1/version", headers={"X-API-Key": "s3cret"}).json()["api_key_required"]
