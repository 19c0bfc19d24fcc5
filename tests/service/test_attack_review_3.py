"""Review of the check workers (merge 2ed4d37): findings as failing tests.

1. One key's render submissions fill the shared check workers (no per-key bound on a
   render's check, FIFO queue): another key's valid upload waits out the deadline and is
   answered 422 "reading it took longer" (its file blamed) or 503.
2. POST /v1/fits reads every data file whole in the web process (route thread; a wide CSV
   with the sidecar: 35 MiB took 15.6 s and +109 MiB there, no deadline, no memory bound).
3. POST /v1/tables with a measured model reads the file in the web process
   (tabulate.normalise builds `Measured`, which reads the file at once): 6 reads per request.
"""
from __future__ import annotations

import threading
from pathlib import Path

import numpy as np

from bsdflab.measured.rgl import write_rgl
from bsdflab.measured.rgl_file import RGLData
from support.service_client import make_client

OCTETS = {"content-type": "application/octet-stream"}
KEYS = {"a": {"key": "a-key-0123456789abcdef"}, "b": {"key": "b-key-0123456789abcdef"}}
A, B = {"X-API-Key": KEYS["a"]["key"]}, {"X-API-Key": KEYS["b"]["key"]}
EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "fit"


def rgl_bytes(tmp_path, n_theta=2, channels=4, n=8, name="f.bsdf") -> bytes:
    """A valid spectral RGL file (8 x 32 x 128 x 128: 16 MiB, seconds to check)."""
    theta = np.linspace(0, 1.4, n_theta).astype(np.float32)
    data = RGLData(description=name, jacobian=True, theta_i=theta, phi_i=np.zeros(1, np.float32),
                   ndf=np.ones((8, 8), np.float32), sigma=np.ones((8, 8), np.float32),
                   vndf=np.ones((1, n_theta, 8, 8), np.float32), luminance=np.ones((1, n_theta, n, n), np.float32),
                   values=np.full((1, n_theta, channels, n, n), 0.3, np.float32),
                   wavelengths=np.linspace(380, 780, channels).astype(np.float32))
    write_rgl(tmp_path / name, data)
    return (tmp_path / name).read_bytes()


def test_one_keys_renders_do_not_deny_another_keys_upload(tmp_path):
    """Key a names its own (large) measured file in 24 renders at once; key b's small valid
    upload must not wait out the check deadline behind them. Fails at 2ed4d37: b gets 422
    "the upload: reading it took longer than 10 s" (its tiny file blamed for a queue it
    waited in) or 503. Fix: a per-key bound on checks in flight (429 to a's extra renders),
    and the deadline's 422 only for time the check itself ran (503 + Retry-After for the wait)."""
    big = rgl_bytes(tmp_path, 8, 32, 128, "big.bsdf")
    small = rgl_bytes(tmp_path, name="small.bsdf")
    settings = dict(api_keys=KEYS, key_rate_per_s=1000, limit_measured_bytes=32 << 20, limit_body_bytes=1 << 20,
                    check_workers=1, limit_queue=64, limit_queue_per_key=64)
    with make_client(tmp_path, check_deadline_s=300, **settings) as client:   # stored once, unhurried
        r = client.post("/v1/measured", params={"format": "rgl"}, content=big, headers={**A, **OCTETS})
        assert r.status_code == 200, r.text
    with make_client(tmp_path, check_deadline_s=10, **settings) as client:
        material = {"type": "measured", "hash": r.json()["hash"]}
        answers = []

        def render(seed):
            answers.append(client.post("/v1/renders", headers=A, json={
                "scene": "sphere", "width": 4, "height": 4, "spp": 1, "seed": seed,
                "options": {"variant": "full", "material": material}}).status_code)

        threads = [threading.Thread(target=render, args=(seed,)) for seed in range(24)]
        for t in threads:
            t.start()
        threading.Event().wait(1.0)
        victim = client.post("/v1/measured", params={"format": "rgl"}, content=small, headers={**B, **OCTETS})
        for t in threads:
            t.join()
        assert victim.status_code == 200, (victim.status_code, victim.text, answers)


def test_a_fits_data_files_are_not_read_in_the_web_process(tmp_path, monkeypatch):
    """The fit's readers made to fail in this (the web) process, as the upload tripwire of
    test_checks_offloaded: POST /v1/fits must read its data (the wide CSV whole, with the
    sidecar) in a check worker. Fails at 2ed4d37: ``load_dataset`` on the route's thread
    (AssertionError "read in the web process")."""
    from bsdflab.fit import readers

    with make_client(tmp_path, limit_body_bytes=256 << 10) as client:
        r = client.post("/v1/fits/datasets", params={"name": "angles.csv"},
                        content=(EXAMPLES / "wide" / "angles.csv").read_bytes(), headers=OCTETS)
        assert r.status_code == 200, r.text

        def tripwire(*args, **kwargs):
            raise AssertionError("read in the web process")

        monkeypatch.setattr(readers, "import_files", tripwire)
        config = {"parameters": {"film_thickness_nm": {"prior": "normal", "mean": 430.0, "sd": 10.0}},
                  "model": {"thickness_nodes": 1},
                  "sampler": {"walkers": 8, "max_steps": 40, "check_every": 40, "map_starts": 1, "seed": 3},
                  "appearance": {"draws": 4, "renders": 0, "angles_deg": [0, 30]}}
        r = client.post("/v1/fits", json={"config": config, "data": [{"hash": r.json()["hash"], "name": "angles.csv"}],
                                          "sidecar": {"geometry": "specular", "units": "percent"}})
        if r.status_code == 202:
            client.delete(f"/v1/jobs/{r.json()['id']}")
        assert r.status_code in (202, 422), r.text


def test_a_table_of_a_measured_file_is_not_read_in_the_web_process(tmp_path, monkeypatch):
    """POST /v1/tables with {"type": "measured", "hash": h}: the file must be read in a check
    worker (as a render's stored material), not on the route's thread. Fails at 2ed4d37:
    tabulate.normalise builds Measured (read_rgl) in the web process: 6 reads of the whole
    file per request (normalise, key, cells, ...), observed."""
    from bsdflab.measured import measured_bsdf

    with make_client(tmp_path, limit_body_bytes=1 << 20) as client:
        r = client.post("/v1/measured", params={"format": "rgl"}, content=rgl_bytes(tmp_path), headers=OCTETS)
        assert r.status_code == 200, r.text
        reads = []
        real = measured_bsdf.read_rgl
        def counted(path):   # the route's reads; not the job's own (in-process here: make_client's
            if not threading.current_thread().name.startswith("bsdflab-job"):   # thread executor)
                reads.append(path)
            return real(path)

        monkeypatch.setattr(measured_bsdf, "read_rgl", counted)
        r = client.post("/v1/tables", json={"model": {"type": "measured", "hash": r.json()["hash"]},
                                            "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}})
        if r.status_code == 202:
            client.delete(f"/v1/jobs/{r.json()['id']}")
        assert r.status_code in (200, 202), r.text
        assert reads == [], f"{len(reads)} reads of the measured file in the web process"
