"""Issue 33's second red team, the findings at the edges of a request: bounded metric labels
(M5), no other tenant's job named in a 404, /healthz outside the key rate, ``model: null``
refused, huge method strings cut short in the log."""
from __future__ import annotations

import logging
import re

import pytest
from fastapi.testclient import TestClient

from bsdflab.service import Settings, create_app

ALICE, BOB, ROOT = "alice-key-0123456789", "bob-key-0123456789ab", "root-key-0123456789ab"
KEYS = {"alice": {"key": ALICE}, "bob": {"key": BOB, "rate_per_s": 1}, "root": {"key": ROOT, "admin": True}}
LONG = {"preset": "xenopeltis-thin-film", "grid": {"n_theta_i": 12, "n_theta_o": 24, "n_phi": 13},
        "min_samples": 4096, "max_samples": 4096}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    settings = Settings(data_dir=(folder := tmp_path_factory.mktemp("edges")), cache_dir=folder / "tables",
                        executor="threads", workers=1, api_keys=KEYS,
                        progress_interval_s=0.05)
    with TestClient(create_app(settings)) as c:
        yield c


def _label_sets(text: str) -> set[tuple[str, str]]:
    return set(re.findall(r'bsdflab_http_request_duration_seconds_count\{method="([^"]*)",route="([^"]*)"', text))


def test_unknown_methods_and_routes_share_one_label(client):
    """Before: each random method name, without a key, was a new label set (2000 of them
    grew /metrics to 259 MB). Mutation caught: labelling by ``scope["method"]`` again
    gives 40 method labels here."""
    client.get("/metrics", headers={"X-API-Key": ROOT})
    before = _label_sets(client.get("/metrics", headers={"X-API-Key": ROOT}).text)
    for i in range(40):
        client.request(f"X{i:04d}", f"/no/such/route/{i}")
        client.request(f"Y{i:04d}", "/v1/jobs")
    labels = _label_sets(client.get("/metrics", headers={"X-API-Key": ROOT}).text) - before
    assert {method for method, _ in labels} <= {"other"}, labels
    assert len(labels) <= 2, labels


def test_a_404_never_names_another_tenants_job(client):
    """Before: bob's GET /v1/tables/{hash} of alice's running table said "; job <id> is
    running". Mutation caught: the hint without the visibility check."""
    job = client.post("/v1/tables", json=LONG, headers={"X-API-Key": ALICE}).json()
    try:
        for path in (f"/v1/tables/{job['hash']}", f"/v1/tables/{job['hash']}/file"):
            theirs = client.get(path, headers={"X-API-Key": ALICE})
            assert theirs.status_code == 404 and job["id"] in theirs.text   # the owner is told
            other = client.get(path, headers={"X-API-Key": ROOT.replace("root", "nobo")})
            assert other.status_code == 401
        bob = client.get(f"/v1/tables/{job['hash']}", headers={"X-API-Key": BOB})
        assert bob.status_code == 404 and job["id"] not in bob.text and "running" not in bob.text
    finally:
        client.delete(f"/v1/jobs/{job['id']}", headers={"X-API-Key": ALICE})


def test_a_render_never_shows_another_tenants_job(tmp_path):
    """Renders are shared by content hash, their jobs are not: before, bob's GET
    /v1/renders/{hash} of alice's running render answered her job (id, state, progress).
    Mutation caught: ``render_info`` without ``jobs.visible`` (bob sees the job id)."""
    keys = {"alice": {"key": ALICE}, "bob": {"key": BOB}}
    settings = Settings(data_dir=tmp_path, cache_dir=tmp_path / "tables",
                        executor="threads", workers=1, api_keys=keys, progress_interval_s=0.05)
    with TestClient(create_app(settings)) as c:
        job = c.post("/v1/renders", json={"scene": "sphere", "width": 64, "height": 64, "spp": 256},
                     headers={"X-API-Key": ALICE}).json()
        try:
            mine = c.get(f"/v1/renders/{job['hash']}", headers={"X-API-Key": ALICE})
            bob = c.get(f"/v1/renders/{job['hash']}", headers={"X-API-Key": BOB})
            assert mine.status_code == 200 and job["id"] in mine.text
            assert job["id"] not in bob.text and (bob.status_code == 404 or bob.json()["state"] == "done"), bob.text
        finally:
            c.delete(f"/v1/jobs/{job['id']}", headers={"X-API-Key": ALICE})


def test_healthz_is_outside_the_key_rate(client):
    """Before: bob (1 request/s) got 429 on /healthz once over his rate. Mutation caught:
    the bucket taken before the public-path check."""
    codes = [client.get("/healthz", headers={"X-API-Key": BOB}).status_code for _ in range(10)]
    assert codes == [200] * 10
    over = [client.get("/v1/presets", headers={"X-API-Key": BOB}).status_code for _ in range(5)]
    assert 429 in over   # the rate still holds elsewhere


@pytest.mark.parametrize("body", [
    {"model": None, "theta_i": [0], "theta_o": [0]},
    {"model": None, "preset": "xenopeltis", "theta_i": [0], "theta_o": [0]},
    {"preset": None, "model": {"type": "diffuse", "reflectance": 0.5}, "theta_i": [0], "theta_o": [0]},
])
def test_an_explicit_null_model_or_preset_is_refused(client, body):
    """Before: ``"model": null`` beside a preset was accepted (the schema says a dict).
    Mutation caught: dropping the explicit-null check answers 200."""
    r = client.post("/v1/bsdf/eval", json=body, headers={"X-API-Key": ALICE})
    assert r.status_code == 422 and "null" in r.text


def test_a_huge_method_name_is_cut_short_in_the_log(client, caplog):
    """Before: an 8 KB method string was logged whole. Mutation caught: logging
    ``scope["method"]`` uncut."""
    with caplog.at_level(logging.INFO, logger="bsdflab.service.requests"):
        client.request("M" * 8192, "/healthz")
    lines = [r.getMessage() for r in caplog.records if r.name == "bsdflab.service.requests"]
    assert lines and all(len(line) < 400 for line in lines), [len(line) for line in lines]


def test_the_queue_always_leaves_room_for_another_key(tmp_path):
    """Before: keys at their default share could fill the whole queue and a fifth tenant
    got only 429. A key that holds jobs may not take the last ``limit_queue_reserve``
    slots; a key that holds none may. Mutation caught: no reserve (alice takes all four
    slots and bob gets 429)."""
    # its own table cache: an earlier app in this process hands its cache folder down through
    # BSDFLAB_CACHE_DIR, where another test's tables of LONG answer 200 at once
    settings = Settings(data_dir=tmp_path, cache_dir=tmp_path / "tables", executor="threads", workers=1,
                        api_keys=KEYS, limit_queue=4, limit_queue_reserve=1, progress_interval_s=0.05)
    with TestClient(create_app(settings)) as c:
        alice = [c.post("/v1/tables", json={**LONG, "rel_error": 0.1 + 0.01 * i}, headers={"X-API-Key": ALICE})
                 for i in range(4)]
        assert [r.status_code for r in alice] == [202, 202, 202, 429], [r.text for r in alice]
        assert "BSDFLAB_LIMIT_QUEUE_RESERVE" in alice[-1].text
        bob = c.post("/v1/tables", json={**LONG, "rel_error": 0.5}, headers={"X-API-Key": BOB})
        assert bob.status_code == 202, bob.text
        for r in (*alice[:3], bob):
            c.delete(f"/v1/jobs/{r.json()['id']}", headers={"X-API-Key": ROOT})
