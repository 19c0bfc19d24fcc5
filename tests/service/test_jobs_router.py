"""/v1/jobs through TestClient: shared jobs, server-sent events, cancelling."""
from __future__ import annotations

import pytest

from support.service_client import LONG_TABLE, TINY_TABLE, make_client, wait_job


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("jobs")) as c:
        yield c


def test_identical_requests_share_one_job_and_cancel(client):
    finished = client.post("/v1/tables", json=TINY_TABLE).json()
    wait_job(client, finished["id"])
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
