"""/v1/validations (issue 33, "validations as jobs"): the report of ``bsdflab validate`` run as
a job, its HTML and JSON as artefacts by hash, cancellable, under the job limits."""
from __future__ import annotations

import json

import pytest

from support.service_client import make_client, wait_job

ONE = {"level": "quick", "only": "tables/diffuse-exact"}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("validations")) as c:
        yield c


def test_a_report_as_a_job(client):
    """The job's report is the registry's check, with the results document the CLI writes;
    the same request again answers 200 from the store."""
    r = client.post("/v1/validations", json=ONE)
    assert r.status_code == 202, r.text
    job = wait_job(client, r.json()["id"], timeout=300)
    assert job["state"] == "done", job
    info = client.get(job["links"]["artefact"]).json()
    assert info["summary"]["total"] == 1 and info["summary"]["pass"] == 1 and info["exit_status"] == 0
    doc = json.loads(client.get(info["links"]["json"]).content)
    assert [c["name"] for c in doc["checks"]] == ["tables/diffuse-exact"] and doc["level"] == "quick"
    html = client.get(info["links"]["html"])
    assert html.status_code == 200 and html.headers["content-type"].startswith("text/html")
    assert "tables/diffuse-exact" in html.text
    again = client.post("/v1/validations", json=ONE)
    assert again.status_code == 200 and again.json()["hash"] == info["hash"]


def test_a_validation_is_cancelled_between_checks(client):
    r = client.post("/v1/validations", json={"level": "quick", "only": "basic/"})
    assert r.status_code == 202, r.text
    assert client.delete(f"/v1/jobs/{r.json()['id']}").status_code == 200
    job = wait_job(client, r.json()["id"], timeout=300)
    assert job["state"] == "cancelled", job
    assert client.get(f"/v1/validations/{job['hash']}/report.html").status_code == 404


@pytest.mark.parametrize("body, words", [
    ({"level": "full"}, "BSDFLAB_LIMIT_VALIDATION_LEVEL"),
    ({"only": "no-such-check-anywhere"}, "matches no check"),
    ({"level": "fast"}, "level"),
    ({"only": ""}, "only"),
])
def test_bad_validation_requests_are_422(client, body, words):
    r = client.post("/v1/validations", json=body)
    assert r.status_code == 422 and words in r.text, r.text


def test_benchmarks_are_under_the_level_cap(tmp_path):
    """A quick report's benchmarks run at level standard (bench_thin_film and bench_layered,
    minutes of CPU, up to 900 s each and not cancellable); a server capped at quick
    accepted them with 202. Mutation caught: checking only ``level`` against the cap."""
    with make_client(tmp_path, limit_validation_level="quick") as capped:
        r = capped.post("/v1/validations", json={**ONE, "benchmarks": True})
        assert r.status_code == 422 and "benchmarks" in r.text and "BSDFLAB_LIMIT_VALIDATION_LEVEL" in r.text, r.text


def test_families_are_listed_and_select_checks(client):
    """GET /v1/validations/families lists every family with its checks; a request naming
    families runs only theirs (with ``only`` narrowing further)."""
    from bsdflab.validation import FAMILIES

    listed = client.get("/v1/validations/families")
    assert listed.status_code == 200
    assert [f["name"] for f in listed.json()] == list(FAMILIES)
    assert all(f["checks"] > 0 for f in listed.json()), listed.json()
    r = client.post("/v1/validations", json={"level": "quick", "families": ["tables"], "only": "diffuse-exact"})
    assert r.status_code == 202, r.text
    job = wait_job(client, r.json()["id"], timeout=300)
    assert job["state"] == "done", job
    info = client.get(job["links"]["artefact"]).json()
    assert info["request"]["families"] == ["tables"] and info["summary"]["total"] == 1


@pytest.mark.parametrize("body", [{"families": ["nope"]}, {"families": []}, {"families": "tables"}])
def test_unknown_families_are_422_listing_the_valid_ones(client, body):
    r = client.post("/v1/validations", json=body)
    assert r.status_code == 422, r.text
    if body["families"] == ["nope"]:
        assert "solvers" in r.text and "coverage" in r.text and "service" in r.text, r.text


def test_families_and_only_that_match_nothing_are_422(client):
    r = client.post("/v1/validations", json={"families": ["fit"], "only": "tables/"})
    assert r.status_code == 422 and "matches no check" in r.text, r.text
