"""/v1/jobs through TestClient: shared jobs, server-sent events, cancelling."""
from __future__ import annotations

import pytest

from support.liveness import wait_until
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


def test_progress_streams_per_key_are_capped_and_released(tmp_path):
    """A progress stream outlives every connection timeout: before, one key could hold as
    many as it liked (300 on one job held /v1/jobs up for 2 s; 512 reach the connection
    cap). Two streams open, the third is 429; when the job ends the streams end and their
    slots come back. Mutation caught: no ``stream_slot`` (the third stream opens, 200)."""
    import contextlib

    with make_client(tmp_path, limit_event_streams_per_key=2) as client:
        job_id = client.post("/v1/tables", json=LONG_TABLE).json()["id"]
        wait_job(client, job_id, states=("running",))
        with contextlib.ExitStack() as stack:
            streams = [stack.enter_context(client.stream("GET", f"/v1/jobs/{job_id}/events")) for _ in range(3)]
            stack.callback(client.delete, f"/v1/jobs/{job_id}")   # first on the way out: the streams end
            assert [s.status_code for s in streams] == [200, 200, 429]
            assert "BSDFLAB_LIMIT_EVENT_STREAMS_PER_KEY" in streams[2].read().decode()
            client.delete(f"/v1/jobs/{job_id}")
            for s in streams[:2]:
                assert [line for line in s.iter_lines() if line.startswith("event:")][-1] == "event: cancelled"
        wait_until(lambda: not client.app.state.event_streams, "end of the event streams")
        again = client.get(f"/v1/jobs/{job_id}/events")   # the job has finished: one event
        assert again.status_code == 200 and "event: cancelled" in again.text
