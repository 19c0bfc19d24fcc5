"""The HTTP contract: what the schema says is what the server does (chunked bodies, exclusive
fields, empty lists and strings, strict integers, 405 Allow, HEAD), request ids, metrics."""
from __future__ import annotations

import logging

import pytest
from fastapi.testclient import TestClient

from bsdflab.service import Settings, create_app
from bsdflab.service.logs import log_config

DIFFUSE = {"type": "diffuse", "reflectance": 0.5}
ANGLES = {"theta_i": [0], "theta_o": [0]}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    settings = Settings(data_dir=(folder := tmp_path_factory.mktemp("contract")), cache_dir=folder / "tables",
                        executor="threads", workers=1,
                        limit_body_bytes=64 << 10)
    with TestClient(create_app(settings)) as c:
        yield c


def test_a_chunked_body_over_the_limit_is_413(client):
    """Before: 400 "There was an error parsing the body"."""
    def chunks():
        for _ in range(100):
            yield b" " * 1024

    r = client.post("/v1/bsdf/eval", content=chunks(), headers={"content-type": "application/json"})
    assert r.status_code == 413 and "BSDFLAB_LIMIT_BODY_BYTES" in r.text

    def small():
        yield b'{"model": {"type": "diffuse", "reflectance": 0.5}, '
        yield b'"theta_i": [0], "theta_o": [0]}'

    assert client.post("/v1/bsdf/eval", content=small(),
                       headers={"content-type": "application/json"}).status_code == 200


def test_the_schema_says_model_and_preset_exclude_each_other(client):
    schema = client.get("/openapi.json").json()["components"]["schemas"]["EvalRequest"]
    assert schema["oneOf"] == [{"required": ["model"], "not": {"required": ["preset"]}},
                               {"required": ["preset"], "not": {"required": ["model"]}}]
    assert "null" not in str(schema["properties"]["model"]) and "null" not in str(schema["properties"]["preset"])


@pytest.mark.parametrize("route, body", [
    ("/v1/thinfilm/spectrum", {"angles": []}),
    ("/v1/thinfilm/spectrum", {"wavelengths": []}),
    ("/v1/thinfilm/spectrum", {"angles": [False]}),
    ("/v1/thinfilm/spectrum", {"film_ior": True}),
    ("/v1/bsdf/eval", {"model": DIFFUSE, "wi": [[0, 0, True]], "wo": [[0, 0, 1]]}),
    ("/v1/bsdf/eval", {"model": DIFFUSE, "theta_i": [], "theta_o": [0]}),
    ("/v1/bsdf/eval", {"model": DIFFUSE, "wi": [], "wo": [[0, 0, 1]]}),
    ("/v1/bsdf/eval", {"preset": "", **ANGLES}),
    ("/v1/renders", {"scene": ""}),
    ("/v1/bsdf/eval", {"model": DIFFUSE, **ANGLES, "seed": False}),
    ("/v1/bsdf/eval", {"model": DIFFUSE, **ANGLES, "samples": True}),
    ("/v1/bsdf/eval", {"model": DIFFUSE, **ANGLES, "seed": "1"}),
    ("/v1/bsdf/eval", {"model": DIFFUSE, **ANGLES, "seed": 1.5}),
    ("/v1/bsdf/lobe", {"model": DIFFUSE, "points": True}),
    ("/v1/renders", {"scene": "furnace", "width": True}),
    ("/v1/tables", {"model": DIFFUSE, "seed": False}),
])
def test_empty_and_non_integer_values_are_refused_by_the_schema(client, route, body):
    """Before: these passed the schema (false was the integer 0) and failed later or not at all."""
    r = client.post(route, json=body)
    assert r.status_code == 422, r.text
    assert isinstance(r.json()["detail"], list)     # pydantic's, naming the field


def test_an_integral_number_is_an_integer(client):
    """JSON Schema's "integer" includes 3.0: a schema-valid request must not be refused for it."""
    r = client.post("/v1/bsdf/eval", json={"model": DIFFUSE, **ANGLES, "seed": 3.0})
    assert r.status_code == 200, r.text


def test_empty_query_values_are_refused(client):
    r = client.get("/v1/bsdf/lobe.png", params={"preset": ""})
    assert r.status_code == 422 and isinstance(r.json()["detail"], list)


def test_405_names_every_method_and_head_answers(client):
    """Before: Allow named one method of two, and HEAD on GET routes was 405."""
    r = client.put("/v1/tables")
    assert r.status_code == 405 and r.headers["allow"] == "GET, HEAD, POST"
    r = client.patch("/v1/jobs/" + "0" * 32)
    assert r.status_code == 405 and r.headers["allow"] == "DELETE, GET, HEAD"
    for path in ("/healthz", "/v1/presets", "/", "/static/app.js"):
        head, get = client.head(path), client.get(path)
        assert head.status_code == get.status_code == 200 and head.content == b"", path
        assert head.headers["content-type"] == get.headers["content-type"]


def test_request_ids_reach_the_log_lines(client, caplog):
    with caplog.at_level(logging.INFO, logger="bsdflab.service"):
        r = client.get("/v1/presets", headers={"X-Request-ID": "abc-123"})
        forged = client.get("/v1/presets", headers={"X-Request-ID": "bad id; forged"})
    assert r.headers["x-request-id"] == "abc-123"
    assert forged.headers["x-request-id"] != "bad id; forged" and len(forged.headers["x-request-id"]) == 16
    lines = [rec.getMessage() for rec in caplog.records if rec.name == "bsdflab.service.requests"]
    assert any(line.startswith('GET "/v1/presets" 200') for line in lines)
    config = log_config("info", json_lines=True)
    assert config["loggers"]["uvicorn.access"]["handlers"] == [] and "one" in config["handlers"]


def test_metrics(client):
    client.post("/v1/bsdf/eval", json={"preset": "xenopeltis", **ANGLES, "samples": 8})
    text = client.get("/metrics").text
    for name in ("bsdflab_http_request_duration_seconds_bucket", "bsdflab_heavy_in_flight", "bsdflab_heavy_slots",
                 "bsdflab_heavy_refused_total", "bsdflab_job_queue_depth", "bsdflab_eval_walks_total 8.0"):
        assert name in text, name
    assert 'route="/v1/bsdf/eval"' in text
