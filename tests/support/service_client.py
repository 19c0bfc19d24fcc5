"""The HTTP API in process (FastAPI's TestClient) for the router tests: small limits, jobs
on the thread executor (worker processes and a real server: the *_live tests)."""
from __future__ import annotations

import json
import time

from fastapi.testclient import TestClient

from bsdflab.service import Settings, create_app

DIFFUSE = {"type": "diffuse", "reflectance": 0.5}
TINY_TABLE = {"model": DIFFUSE, "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}}
# a layered table long enough to still be running when the test looks (many cells, cancelled)
LONG_TABLE = {"preset": "xenopeltis-thin-film", "grid": {"n_theta_i": 12, "n_theta_o": 24, "n_phi": 13},
              "min_samples": 4096, "max_samples": 4096, "method": "pfmc"}


def make_client(tmp_path, **settings) -> TestClient:
    defaults = {"data_dir": tmp_path, "cache_dir": tmp_path / "tables", "executor": "threads", "workers": 1,
                "limit_directions": 500,
                "limit_body_bytes": 64 << 10, "limit_queue": 3, "limit_table_cells": 50_000,
                "progress_interval_s": 0.05}
    return TestClient(create_app(Settings(**{**defaults, **settings})))


def detail(response) -> str:
    return json.dumps(response.json()["detail"])


def wait_job(client, job_id, states=("done", "failed", "cancelled"), timeout=120, headers=None):
    end = time.monotonic() + timeout
    while True:
        job = client.get(f"/v1/jobs/{job_id}", headers=headers).json()
        if job["state"] in states:
            return job
        assert time.monotonic() < end, job
        time.sleep(0.05)
