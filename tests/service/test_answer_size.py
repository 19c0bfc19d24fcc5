"""Answers are bounded before computing (pairs x channels, lobe grids), and large
evaluations have a compact binary form (docs/service.md, "Bounded work")."""
from __future__ import annotations

import io

import numpy as np
import pytest
from fastapi.testclient import TestClient

from bsdflab.service import Settings, create_app

DIFFUSE = {"type": "diffuse", "reflectance": 0.5}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    settings = Settings(data_dir=tmp_path_factory.mktemp("size"), executor="threads", workers=1,
                        limit_body_bytes=1 << 20)
    with TestClient(create_app(settings)) as c:
        yield c


def test_pairs_times_channels_is_capped_before_computing(client):
    """Before: 20 000 pairs x 1 024 wavelengths of a diffuse model (a 164 KB request) was
    answered with 408 MB of JSON."""
    body = {"model": DIFFUSE, "theta_i": [30.0], "theta_o": list(np.linspace(0, 80, 20_000)),
            "wavelengths": list(np.linspace(380, 780, 1024))}
    r = client.post("/v1/bsdf/eval", json=body)
    assert r.status_code == 422 and "BSDFLAB_LIMIT_RESPONSE_BYTES" in r.text and "20000 pairs x 1024" in r.text
    r = client.post("/v1/bsdf/eval", json=body, headers={"Accept": "application/x-npy"})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_RESPONSE_BYTES" in r.text


def test_lobe_grids_are_capped(tmp_path):
    settings = Settings(data_dir=tmp_path, executor="threads", workers=1, limit_response_bytes=1 << 20)
    with TestClient(create_app(settings)) as c:
        r = c.post("/v1/bsdf/lobe", json={"model": DIFFUSE, "resolution": 181, "points": 181})
        assert r.status_code == 422 and "BSDFLAB_LIMIT_RESPONSE_BYTES" in r.text
        assert c.post("/v1/bsdf/lobe", json={"model": DIFFUSE, "resolution": 33}).status_code == 200


@pytest.mark.parametrize("body", [
    {"model": DIFFUSE, "theta_i": [0, 30, 60], "theta_o": [10, 45, 80], "wavelengths": [450, 550, 650, 700]},
    {"preset": "xenopeltis", "theta_i": [20], "theta_o": [20, 40], "samples": 16, "seed": 3},
])
def test_binary_answer_equals_the_json_one(client, body):
    as_json = client.post("/v1/bsdf/eval", json=body).json()
    r = client.post("/v1/bsdf/eval", json=body, headers={"Accept": "application/x-npy"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/x-npy"
    array = np.load(io.BytesIO(r.content), allow_pickle=False)
    assert r.headers["x-shape"] == ",".join(map(str, array.shape))
    assert r.headers["x-channels"].split(",") == as_json["channels"]
    if as_json["stochastic"]:
        assert r.headers["x-layout"] == "values,stderr" and array.shape[0] == 2
        np.testing.assert_array_equal(array[0], as_json["values"])
        np.testing.assert_array_equal(array[1], as_json["stderr"])
    else:
        assert r.headers["x-layout"] == "values"
        np.testing.assert_array_equal(array, as_json["values"])
