"""The heavy pool in process: a request past its compute deadline stops with a 422 naming
the setting, and its thread is free again (the saturation and disconnect tests run a real
server: test_saturation_live.py)."""
from __future__ import annotations

import time

from fastapi.testclient import TestClient

from bsdflab.service import Settings, create_app

# 16 pairs at 16 384 walks: 16 C++ calls of about a CPU-second each
LONG_EVAL = {"preset": "xenopeltis", "theta_i": [30], "theta_o": [float(x) for x in range(5, 85, 5)],
             "samples": 16_384}


def test_a_request_past_its_deadline_stops(tmp_path):
    """Before: no deadline (2^24 walks of xenopeltis, allowed, were 15 CPU-minutes)."""
    settings = Settings(data_dir=tmp_path, cache_dir=tmp_path / "tables",
                        executor="threads", workers=1, compute_deadline_s=0.5,
                        heavy_concurrency=1)
    with TestClient(create_app(settings)) as client:
        one = {**LONG_EVAL, "theta_o": [40.0]}
        client.post("/v1/bsdf/eval", json={**one, "samples": 16})     # builds the model's core objects
        t = time.perf_counter()
        client.post("/v1/bsdf/eval", json=one)                       # one C++ call of the long request
        call = time.perf_counter() - t
        t = time.perf_counter()
        r = client.post("/v1/bsdf/eval", json=LONG_EVAL)
        took = time.perf_counter() - t
        assert r.status_code == 422 and "BSDFLAB_COMPUTE_DEADLINE_S" in r.text, r.text
        # all 16 calls would take 16 x call; it stops after the one in progress at the deadline
        assert took < 4 * call + 1.0, (took, call)
        assert client.app.state.heavy.in_flight == 0
