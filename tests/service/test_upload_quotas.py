"""Findings M6 and M7 of issue 33 and the MERL minor one: uploads have per-key concurrency,
a global bytes-in-flight cap and a per-key storage quota; a stored description is cut to a
preview; a MERL file of absurd values is refused."""
from __future__ import annotations

import asyncio

import numpy as np
import pytest

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import export_model
from bsdflab.measured.merl import DIMS
from bsdflab.measured.rgl import write_rgl
from bsdflab.measured.rgl_file import read_rgl
from bsdflab.service.auth import Client
from bsdflab.service.upload_gate import UploadGate
from bsdflab.service.uploads import DESCRIPTION_PREVIEW
from support.liveness import HANG_S
from support.service_client import make_client


def _upload(client, data: bytes, fmt: str = "rgl"):
    return client.post("/v1/measured", params={"format": fmt}, content=data,
                       headers={"content-type": "application/octet-stream"})


@pytest.fixture(scope="module")
def rgl_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("quota-files")
    paths = []
    for i, alpha in enumerate((0.2, 0.3, 0.4)):
        export_model(RoughConductor(alpha=alpha, material="Cu"), folder / f"{i}.bsdf", n_theta_i=4, resolution=8,
                     error_points=100)
        paths.append(folder / f"{i}.bsdf")
    return paths


def test_a_clients_stored_uploads_are_capped(tmp_path, rgl_files):
    """Before: no quota (48 uploads put 2 GB on disk). Two files fit the quota, the third
    is refused naming it; the same bytes again cost nothing. Mutation caught: no storage
    check (the third answers 200)."""
    size = max(p.stat().st_size for p in rgl_files)
    with make_client(tmp_path, limit_measured_bytes=1 << 20, limit_upload_storage_per_key=2 * size + 10) as client:
        assert _upload(client, rgl_files[0].read_bytes()).status_code == 200
        assert _upload(client, rgl_files[1].read_bytes()).status_code == 200
        assert _upload(client, rgl_files[0].read_bytes()).status_code == 200   # already stored
        r = _upload(client, rgl_files[2].read_bytes())
        assert r.status_code == 413 and "BSDFLAB_LIMIT_UPLOAD_STORAGE_PER_KEY" in r.text, r.text


def test_concurrent_uploads_per_key_and_bytes_in_flight(tmp_path):
    """The gate in front of POST /v1/measured, driven directly: uploads held open by their
    (never finishing) handler. Mutation caught: no per-key count (the third of alice's
    gets through) or no global byte count (bob's big one gets through)."""
    release = asyncio.Event()

    async def held(scope, receive, send):
        await release.wait()
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b""})

    class Settings:
        limit_uploads_per_key, limit_upload_bytes_in_flight = 2, 3000
        limit_upload_storage_per_key, limit_measured_bytes = 1 << 30, 1 << 20

    def scope(who: str, size: int) -> dict:
        return {"type": "http", "method": "POST", "path": "/v1/measured", "state": {"client": Client(who)},
                "headers": [(b"content-length", str(size).encode())]}

    async def run() -> list[int]:
        gate = UploadGate(held, Settings(), stored_bytes=lambda client: 0)
        statuses: list[int] = []

        async def call(who, size):
            sent = []

            async def send(message):
                if message["type"] == "http.response.start":
                    sent.append(message["status"])

            await gate(scope(who, size), None, send)
            statuses.append(sent[0])

        tasks = [asyncio.create_task(call("alice", 1000)), asyncio.create_task(call("alice", 1000))]
        await asyncio.sleep(0.01)
        await call("alice", 10)      # a third of alice's at once: 429
        await call("bob", 1500)      # 2000 + 1500 bytes over the 3000 in flight: 429
        tasks.append(asyncio.create_task(call("bob", 900)))   # fits
        await asyncio.sleep(0.01)
        release.set()
        await asyncio.gather(*tasks)
        return statuses

    statuses = asyncio.run(asyncio.wait_for(run(), 30))
    assert statuses[:2] == [429, 429] and statuses[2:] == [200, 200, 200], statuses


def test_a_long_description_is_stored_as_a_preview(tmp_path, rgl_files):
    """Before: a 60 MiB description was stored and echoed in every listing (377 MB).
    Mutation caught: storing ``d.description`` whole (the listing carries 200 000 chars)."""
    data = read_rgl(rgl_files[0])
    long = tmp_path / "long.bsdf"
    write_rgl(long, data.__class__(**{**data.__dict__, "description": "x" * 200_000}))
    with make_client(tmp_path / "d", limit_measured_bytes=4 << 20) as client:
        r = _upload(client, long.read_bytes())
        assert r.status_code == 200, r.text
        listed = client.get("/v1/measured").json()["measured"][0]["summary"]
        assert len(listed["description"]) <= DESCRIPTION_PREVIEW + 1 and listed["description_chars"] == 200_000
        assert len(client.get("/v1/measured").content) < 8192


def test_a_merl_file_of_absurd_values_is_refused(tmp_path):
    """Before: 1e308 everywhere was accepted and evaluated to null. Mutation caught: no
    magnitude check in ``read_merl`` (200)."""
    with make_client(tmp_path, limit_measured_bytes=40 << 20) as client:
        raw = np.array(DIMS, dtype="<i4").tobytes() + np.full((3, *DIMS), 1e308, dtype="<f8").tobytes()
        r = _upload(client, raw, "merl")
        assert r.status_code == 422 and "MERL" in r.text, r.text


def test_an_upload_declared_over_the_cap_is_413_not_retry_later(tmp_path):
    """A body declared larger than ``BSDFLAB_LIMIT_MEASURED_BYTES`` and than the bytes in
    flight was a 429 with Retry-After (a client retries for ever what can never pass).
    Mutation caught: the gate counting the declared size uncapped (429)."""
    with make_client(tmp_path, limit_measured_bytes=1 << 20, limit_upload_bytes_in_flight=2 << 20) as client:
        r = client.post("/v1/measured", params={"format": "merl"}, content=b"x" * (3 << 20))
        assert r.status_code == 413 and "BSDFLAB_LIMIT_MEASURED_BYTES" in r.text, r.text


def test_concurrent_uploads_of_one_key_do_not_overshoot_its_quota(tmp_path, rgl_files):
    """Two uploads of one key at once (its default concurrency) each passed the quota
    check before either was stored: both 200, the quota passed by a file. The file's check
    (awaited on the event loop) is made to wait (up to 3 s) for the other upload's, so
    without the per-client turn the two always overlap. Mutation caught: no turn around
    check and store (two 200s)."""
    import asyncio
    import threading

    size = max(p.stat().st_size for p in rgl_files)
    with make_client(tmp_path, limit_measured_bytes=1 << 20, limit_upload_storage_per_key=size + 10) as client:
        checker = client.app.state.jobs.checker
        run_async, arrived = checker.run_async, []

        async def waiting_check(*args, **kwargs):
            arrived.append(1)
            for _ in range(150):   # the other upload's check, or 3 s
                if len(arrived) >= 2:
                    break
                await asyncio.sleep(0.02)
            return await run_async(*args, **kwargs)

        checker.run_async = waiting_check
        codes = []
        threads = [threading.Thread(target=lambda p=p: codes.append(_upload(client, p.read_bytes()).status_code))
                   for p in rgl_files[:2]]
        for t in threads:
            t.start()
        for t in threads:
            t.join(HANG_S)
        assert sorted(codes) == [200, 413], codes
