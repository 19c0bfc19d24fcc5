"""Issue 33, item 1: uploads are read in check worker processes (bsdflab.service.offload),
not in the web process, where a 64 MiB file held the GIL (and, inline, the event loop)
while it parsed; the check has a memory bound and a deadline, each a 4xx/503 with a
message, never a 500."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import export_model
from bsdflab.measured.merl import DIMS, merl_bytes
from bsdflab.service import fit_uploads, uploads
from support.service_client import make_client

LONG = (Path(__file__).resolve().parents[2] / "examples" / "fit" / "data.csv").read_bytes()
OCTETS = {"content-type": "application/octet-stream"}


@pytest.fixture(scope="module")
def rgl(tmp_path_factory) -> bytes:
    path = tmp_path_factory.mktemp("offload") / "cu.bsdf"
    export_model(RoughConductor(alpha=0.2, material="Cu"), path, n_theta_i=4, resolution=8, error_points=100)
    return path.read_bytes()


def test_uploads_are_read_outside_the_web_process(tmp_path, rgl, monkeypatch):
    """The readers' entry points are made to fail in this (the web) process: the check
    workers, spawned, import the real ones. Both uploads answer their summaries, read by
    a process that is not this one. Mutation caught (run once): the upload calling
    ``read_summary`` inline instead of the check worker (it raises "read in the web process")."""
    def tripwire(*args, **kwargs):
        raise AssertionError("read in the web process")

    monkeypatch.setattr(uploads, "read_summary", tripwire)
    monkeypatch.setattr(fit_uploads, "read_summary", tripwire)
    with make_client(tmp_path, limit_measured_bytes=1 << 20) as client:
        r = client.post("/v1/measured", params={"format": "rgl"}, content=rgl, headers=OCTETS)
        assert r.status_code == 200 and r.json()["summary"]["n_theta_i"] == 4, r.text
        r = client.post("/v1/fits/datasets", params={"name": "data.csv"}, content=LONG, headers=OCTETS)
        assert r.status_code == 200 and r.json()["summary"]["rows"] > 0, r.text
        pids = client.app.state.jobs.checker.worker_pids()
        assert pids and os.getpid() not in pids
        # a file that does not read: the reader's message, as before (a 422 naming the format)
        r = client.post("/v1/measured", params={"format": "rgl"}, content=b"not an RGL file", headers=OCTETS)
        assert r.status_code == 422 and "format=rgl" in r.text and str(tmp_path) not in r.text, r.text


def test_a_check_past_its_memory_bound_is_413_and_the_worker_goes_on(tmp_path, rgl):
    """A MERL file (35 MB of doubles) read with 16 MiB of memory to spare: 413 naming the
    bound; the same worker then reads a small file (the bound is lifted after each check).
    Mutation caught (run once): ``memory_bound`` a no-op (200)."""
    merl = merl_bytes(0.01 + 0.5 * np.random.default_rng(5).random((3, *DIMS)))
    with make_client(tmp_path, limit_measured_bytes=40 << 20, limit_check_memory_bytes=16 << 20,
                     check_workers=1) as client:
        r = client.post("/v1/measured", params={"format": "merl"}, content=merl, headers=OCTETS)
        assert r.status_code == 413 and "BSDFLAB_LIMIT_CHECK_MEMORY_BYTES" in r.text, r.text
        r = client.post("/v1/measured", params={"format": "rgl"}, content=rgl, headers=OCTETS)
        assert r.status_code == 200, r.text
        assert client.get("/v1/measured").json()["measured"][0]["format"] == "rgl"   # the MERL file not stored


def test_a_check_past_its_deadline_answers_a_4xx_or_503_naming_it(tmp_path, rgl):
    """A deadline shorter than a worker's start: the check is given up (422 when it had
    started, 503 with Retry-After when it was still waiting for a worker; which of the two
    depends on the machine, both name the setting), never a 500, and nothing is stored."""
    with make_client(tmp_path, limit_measured_bytes=1 << 20, check_deadline_s=0.001) as client:
        r = client.post("/v1/measured", params={"format": "rgl"}, content=rgl, headers=OCTETS)
        assert r.status_code in (422, 503) and "BSDFLAB_CHECK_DEADLINE_S" in r.text + str(r.headers), r.text
        if r.status_code == 503:
            assert r.headers["retry-after"]
        assert client.get("/v1/measured").json()["measured"] == []


def test_a_keys_check_beyond_its_share_is_429_before_it_is_queued(tmp_path, rgl):
    """BSDFLAB_LIMIT_CHECKS_PER_KEY (1): while key a holds its check (held here by its slot,
    so no race decides it), a's upload is 429 with Retry-After naming the setting and no
    check is sent to a worker; key b's upload is read. Mutation caught (run once): the slot
    not counted (a's upload 200)."""
    keys = {"a": {"key": "a-key-0123456789abcdef"}, "b": {"key": "b-key-0123456789abcdef"}}
    with make_client(tmp_path, api_keys=keys, key_rate_per_s=1000, limit_measured_bytes=1 << 20) as client:
        checker = client.app.state.jobs.checker
        with checker._slot("a"):
            sent = checker.submitted
            r = client.post("/v1/measured", params={"format": "rgl"}, content=rgl,
                            headers={**OCTETS, "X-API-Key": keys["a"]["key"]})
            assert r.status_code == 429 and r.headers["Retry-After"], r.text
            assert "BSDFLAB_LIMIT_CHECKS_PER_KEY" in r.text and checker.submitted == sent
            r = client.post("/v1/measured", params={"format": "rgl"}, content=rgl,
                            headers={**OCTETS, "X-API-Key": keys["b"]["key"]})
            assert r.status_code == 200, r.text


def test_an_upload_holds_no_route_thread_while_its_check_runs(tmp_path, rgl):
    """Measured and fit-data uploads await their check on the event loop: while the check
    runs, no thread of the route pool (anyio's default limiter, shared by every sync route)
    is borrowed. Before, the whole upload ran on a route thread and waited there (the
    check's wrapper was never awaited: no reading, the test fails)."""
    import anyio.to_thread

    with make_client(tmp_path, limit_measured_bytes=1 << 20) as client:
        checker = client.app.state.jobs.checker
        run_async, borrowed = checker.run_async, []

        async def counting(*args, **kwargs):
            borrowed.append(anyio.to_thread.current_default_thread_limiter().borrowed_tokens)
            return await run_async(*args, **kwargs)

        checker.run_async = counting
        r = client.post("/v1/measured", params={"format": "rgl"}, content=rgl, headers=OCTETS)
        assert r.status_code == 200, r.text
        r = client.post("/v1/fits/datasets", params={"name": "data.csv"}, content=LONG, headers=OCTETS)
        assert r.status_code == 200, r.text
    assert borrowed == [0, 0]
