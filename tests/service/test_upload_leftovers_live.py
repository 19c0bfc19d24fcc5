"""An upload is written to a private folder of the artefact folder and read there by a check
worker before it enters the store. A server killed during that check (SIGKILL, a crash, the
OOM killer) cannot remove the folder; the next server on the data folder does, at start.
Real `bsdflab serve` processes: the check is held by stopping the check worker (SIGSTOP),
so the server dies while the upload's folder exists, whatever the machine's speed."""

from __future__ import annotations

import os
import signal
import threading
import time

import httpx2 as httpx

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import export_model
from support.service_process import ServiceProcess

OCTETS = {"content-type": "application/octet-stream"}


def _rgl(folder, alpha: float) -> bytes:
    path = folder / f"{alpha}.bsdf"
    export_model(RoughConductor(alpha=alpha, material="Cu"), path, n_theta_i=4, resolution=8, error_points=100)
    return path.read_bytes()


def _private_folders(artefacts) -> list[str]:
    return sorted(p.name for p in artefacts.iterdir() if p.is_dir() and p.name.startswith("."))


def test_a_server_killed_during_an_uploads_check_leaves_no_folder_behind(tmp_path):
    """Before: the killed upload's folder (its file inside, up to BSDFLAB_LIMIT_MEASURED_BYTES)
    stayed in the artefact folder for good: no quota counts it and no start removed it (a
    measured upload's temporary file before da0a7d6 was removed by the next atomic write).
    Mutation caught: no removal at start (the folder is still there)."""
    files = tmp_path / "files"
    files.mkdir()
    first, second = _rgl(files, 0.2), _rgl(files, 0.3)
    data = tmp_path / "data"
    data.mkdir()
    artefacts = data / "artefacts"
    server = ServiceProcess(data, env={"BSDFLAB_CHECK_WORKERS": "1"})
    stopped: list[int] = []
    try:
        r = httpx.post(
            f"{server.url}/v1/measured", params={"format": "rgl"}, content=first, headers=OCTETS, timeout=120
        )
        assert r.status_code == 200, r.text  # the check worker now runs
        stopped = server.children()
        for pid in stopped:  # the check worker (and the job worker) hold still: no check ends
            os.kill(pid, signal.SIGSTOP)

        def held_upload() -> None:
            try:
                httpx.post(
                    f"{server.url}/v1/measured", params={"format": "rgl"}, content=second, headers=OCTETS, timeout=120
                )
            except httpx.HTTPError:
                pass  # expected: the test kills the server while this upload waits for its check

        threading.Thread(target=held_upload, daemon=True).start()
        end = time.monotonic() + 600  # a hang guard only, never a timing check
        while not _private_folders(artefacts):  # the upload written, its check waiting
            assert time.monotonic() < end, "the upload's folder never appeared"
            time.sleep(0.02)
        left = _private_folders(artefacts)
    finally:
        server.kill()
        for pid in stopped:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    assert _private_folders(artefacts) == left and left, left
    server = ServiceProcess(data)
    try:
        assert _private_folders(artefacts) == []
        r = httpx.post(
            f"{server.url}/v1/measured", params={"format": "rgl"}, content=second, headers=OCTETS, timeout=120
        )
        assert r.status_code == 200, r.text
        assert _private_folders(artefacts) == []
    finally:
        server.stop()
