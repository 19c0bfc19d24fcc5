"""Keys that scope (docs/service.md, "Keys"): every route x {no key, wrong key, another
client's key, an admin key}; the key is checked before the body is read; jobs belong to
their client; per-client queue share and request rate."""
from __future__ import annotations

import re

import pytest
from fastapi.testclient import TestClient

from bsdflab.service import Settings, create_app
from bsdflab.service.auth import is_public
from support.liveness import wait_until

ALICE, BOB, ROOT = "alice-key-0123456789", "bob-key-0123456789ab", "root-key-0123456789ab"
KEYS = {"alice": {"key": ALICE, "max_jobs": 2}, "bob": {"key": BOB, "rate_per_s": 1000},
        "root": {"key": ROOT, "admin": True}}
TINY = {"model": {"type": "diffuse", "reflectance": 0.5}, "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}}
LONG = {"preset": "xenopeltis-thin-film", "grid": {"n_theta_i": 12, "n_theta_o": 24, "n_phi": 13},
        "min_samples": 4096, "max_samples": 4096}
BODIES = {"/v1/bsdf/eval": {"model": {"type": "diffuse", "reflectance": 0.5}, "theta_i": [0], "theta_o": [0]},
          "/v1/bsdf/lobe": {"model": {"type": "diffuse", "reflectance": 0.5}, "points": 5, "resolution": 5},
          "/v1/bsdf/lobe.png": {"model": {"type": "diffuse", "reflectance": 0.5}, "samples": 500},
          "/v1/thinfilm/spectrum": {"angles": [0], "wavelengths": [500]},
          "/v1/tables": TINY, "/v1/renders": {"scene": "furnace", "width": 4, "height": 4, "spp": 1}}


def key(value: str | None) -> dict[str, str]:
    return {} if value is None else {"X-API-Key": value}


def wait_done(client, job_id: str, who: str) -> dict:
    seen = {}

    def ended() -> bool:
        seen.update(client.get(f"/v1/jobs/{job_id}", headers=key(who)).json())
        return seen["state"] in ("done", "failed", "cancelled")

    wait_until(ended, f"end of job {job_id}")
    return seen


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    settings = Settings(data_dir=(folder := tmp_path_factory.mktemp("auth")), cache_dir=folder / "tables",
                        executor="threads", workers=1,
                        api_keys=KEYS, progress_interval_s=0.05)
    with TestClient(create_app(settings)) as client:
        job = client.post("/v1/tables", json=TINY, headers=key(ALICE)).json()
        yield client, wait_done(client, job["id"], ALICE)


# routes outside the OpenAPI schema (the page, static files, docs, metrics)
UNLISTED = [("GET", p) for p in ("/", "/vendor/plotly.min.js", "/static/app.js", "/docs", "/docs/oauth2-redirect",
                                 "/redoc", "/openapi.json", "/metrics")]


def routes(client):
    """(method, path template) of every route: the schema's, and the unlisted ones."""
    paths = client.get("/openapi.json").json()["paths"]
    listed = [(method.upper(), path) for path, item in paths.items() for method in item]
    return sorted(listed) + UNLISTED


def fill(path: str, job: dict) -> str:
    return re.sub(r"\{job_id\}", job["id"], re.sub(r"\{key\}", job["hash"], path))


def call(client, method, path, who):
    body = BODIES.get(path) if method == "POST" else None
    if path.endswith("/events"):   # the stream ends at once: alice's job has finished
        with client.stream(method, path, headers=key(who)) as r:
            return r.status_code, b"".join(r.iter_bytes())
    r = client.request(method, path, json=body, headers=key(who))
    return r.status_code, r.content


def test_every_route_by_every_kind_of_key(served):
    """Before: listing jobs and tables, reading jobs, artefacts and event streams needed no
    key; another client's jobs were visible and cancellable."""
    client, job = served
    seen = set()
    for method, template in routes(client):
        path = fill(template, job)
        seen.add(template)
        anonymous, _ = call(client, method, path, None)
        wrong, _ = call(client, method, path, "x" * 20)
        if is_public(template):
            assert anonymous < 400 and wrong < 400, (method, path, anonymous)
            continue
        assert anonymous == wrong == 401, (method, path, anonymous, wrong)
        other, content = call(client, method, path, BOB)
        admin, _ = call(client, method, path, ROOT)
        if "{job_id}" in template:        # alice's job is no job at all to bob
            assert other == 404, (method, path, other)
            assert admin in (200, 409), (method, path, admin)
        else:
            assert other < 500 and admin < 500 and other != 401 and admin != 401, (method, path, other, admin)
        if method == "GET" and template in ("/v1/jobs", "/v1/tables"):
            assert job["id"].encode() not in content and job["hash"].encode() not in content
    assert {"/v1/jobs", "/v1/jobs/{job_id}", "/v1/jobs/{job_id}/events", "/v1/tables/{key}/file",
            "/v1/renders/{key}/image.png", "/v1/version", "/healthz", "/docs"} <= seen
    listed = client.get("/v1/jobs", headers=key(ROOT)).json()["jobs"]
    assert job["id"] in [j["id"] for j in listed]
    mine = client.get("/v1/jobs", headers=key(ALICE)).json()["jobs"]
    assert [j["id"] for j in mine] == [job["id"]]


def test_the_key_is_checked_before_the_body(served):
    """Before: a body was parsed (and a malformed one answered 422) before the key's 401."""
    client, _ = served
    r = client.post("/v1/bsdf/eval", content=b"{not json" + b" " * 100_000,
                    headers={"content-type": "application/json"})
    assert r.status_code == 401 and r.headers["www-authenticate"] == "Bearer"
    r = client.post("/v1/bsdf/eval", content=b"{}", headers={"content-type": "application/json",
                                                              "Authorization": "Basic " + ALICE})
    assert r.status_code == 401
    for header in ({"X-API-Key": ALICE + " "}, {"X-API-Key": ALICE[:-1]}, {"Authorization": "Bearer"},
                   {"X-API-Key": ""}, {"X-API-Key": ALICE.upper()}):
        assert client.get("/v1/jobs", headers=header).status_code == 401, header
    assert client.get("/v1/jobs", headers={"Authorization": "bearer " + ALICE}).status_code == 200


def test_queue_share_and_rate(tmp_path):
    keys = {**KEYS, "slow": {"key": "slow-key-0123456789ab", "rate_per_s": 1}}
    # its own table cache: after test_tenant_edges in one process, its table of LONG (rel_error
    # 0.1, finished before its cancel) was found through the handed-down BSDFLAB_CACHE_DIR: 200
    settings = Settings(data_dir=tmp_path, cache_dir=tmp_path / "tables", executor="threads", workers=1,
                        api_keys=keys, progress_interval_s=0.05)
    with TestClient(create_app(settings)) as client:
        ids = [client.post("/v1/tables", json={**LONG, "rel_error": e}, headers=key(ALICE)).json()["id"]
               for e in (0.1, 0.2)]
        full = client.post("/v1/tables", json={**LONG, "rel_error": 0.3}, headers=key(ALICE))
        assert full.status_code == 429 and "BSDFLAB_LIMIT_QUEUE_PER_KEY" in full.text and "Retry-After" in full.headers
        # bob joins alice's job: he sees it, but only alice or an admin may cancel it
        joined = client.post("/v1/tables", json={**LONG, "rel_error": 0.1}, headers=key(BOB))
        assert joined.status_code == 202 and joined.json()["id"] == ids[0]
        assert client.delete(f"/v1/jobs/{ids[0]}", headers=key(BOB)).status_code == 403
        assert client.delete(f"/v1/jobs/{ids[1]}", headers=key(BOB)).status_code == 404
        assert client.delete(f"/v1/jobs/{ids[0]}", headers=key(ALICE)).status_code == 200
        assert client.delete(f"/v1/jobs/{ids[1]}", headers=key(ROOT)).status_code == 200
        codes = [client.get("/v1/presets", headers=key("slow-key-0123456789ab")) for _ in range(4)]
        assert [r.status_code for r in codes][:2] == [200, 200] and codes[-1].status_code == 429
        assert int(codes[-1].headers["retry-after"]) >= 1
        for job_id in ids:
            wait_done(client, job_id, ROOT)
