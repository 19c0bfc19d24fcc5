"""How an upload (service/uploads.py, ``stored_after_check``) shares the event loop: its
hashing runs on a route thread, not the loop, and a request cancelled while its file is
being stored (uvicorn cancels requests still running 5 s into a graceful stop) keeps the
key's turn and its private folder until that thread is done."""

from __future__ import annotations

import asyncio
import hashlib
import threading
from pathlib import Path

import httpx2 as httpx
import pytest

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import export_model
from bsdflab.service import uploads
from support.liveness import HANG_S
from support.service_client import make_client

LONG = (Path(__file__).resolve().parents[2] / "examples" / "fit" / "data.csv").read_bytes()
OCTETS = {"content-type": "application/octet-stream"}


@pytest.fixture(scope="module")
def rgl(tmp_path_factory) -> bytes:
    path = tmp_path_factory.mktemp("loop") / "cu.bsdf"
    export_model(RoughConductor(alpha=0.2, material="Cu"), path, n_theta_i=4, resolution=8, error_points=100)
    return path.read_bytes()


def test_an_uploads_hash_is_not_computed_on_the_event_loop(tmp_path, rgl, monkeypatch):
    """Before: the SHA-256 of the body ran on the event loop (50 ms for a 64 MiB upload,
    every other request waiting), where the upload had run on a route thread before
    da0a7d6. Each hash records whether it ran where an event loop runs."""
    on_loop, sha256 = [], hashlib.sha256

    def recording_sha256(data):
        try:
            asyncio.get_running_loop()
            on_loop.append(True)
        except RuntimeError:
            on_loop.append(False)
        return sha256(data)

    monkeypatch.setattr(uploads.hashlib, "sha256", recording_sha256)
    with make_client(tmp_path, limit_measured_bytes=1 << 20) as client:
        r = client.post("/v1/measured", params={"format": "rgl"}, content=rgl, headers=OCTETS)
        assert r.status_code == 200, r.text
        r = client.post("/v1/fits/datasets", params={"name": "data.csv"}, content=LONG, headers=OCTETS)
        assert r.status_code == 200, r.text
    assert on_loop == [False, False]


def test_a_request_cancelled_while_its_file_is_stored_keeps_its_turn_until_stored(tmp_path, rgl):
    """The store's record of the upload is held (its thread waits for the test) and the
    request is cancelled there. Before: the cancel returned at once while the thread went
    on: the private folder was removed under it and the key's turn handed on, so another
    upload of the key passed the quota check before this file was counted. Now both stay
    until the thread is done; then the file is recorded, the folder gone, the turn free.
    The loop is turned 50 times after the cancel (no clock): the request ended within a
    few before."""
    with make_client(tmp_path, limit_measured_bytes=1 << 20) as client:
        jobs, app = client.app.state.jobs, client.app
        put_upload, entered, release = jobs.store.put_upload, threading.Event(), threading.Event()

        def held_put_upload(*args, **kwargs):
            entered.set()
            release.wait(HANG_S)
            return put_upload(*args, **kwargs)

        jobs.store.put_upload = held_put_upload
        lock = uploads.client_lock("anonymous")
        artefacts = jobs.artefact_dir

        def private_folders() -> list[Path]:
            return [p for p in artefacts.iterdir() if p.is_dir() and p.name.startswith(uploads.LEFT_PREFIXES)]

        async def cancelled_upload():
            async with httpx.AsyncClient(transport=httpx.ASGITransport(app=app), base_url="http://test") as ac:
                request = asyncio.ensure_future(
                    ac.post("/v1/measured", params={"format": "rgl"}, content=rgl, headers=OCTETS)
                )
                for _ in range(3000):  # a hang guard: the store's thread reaches the record
                    if entered.is_set():
                        break
                    await asyncio.sleep(0.02)
                assert entered.is_set()
                request.cancel()
                for _ in range(50):
                    await asyncio.sleep(0)
                during = (request.done(), lock.locked(), len(private_folders()))
                release.set()
                with pytest.raises(asyncio.CancelledError):
                    await request
                return during

        during = client.portal.call(cancelled_upload)
        assert during == (False, True, 1)
        assert not lock.locked() and private_folders() == []
        h = hashlib.sha256(rgl).hexdigest()
        assert jobs.store.artefact(h, uploads.KIND) is not None and jobs.store.uploaded(h, "anonymous")
