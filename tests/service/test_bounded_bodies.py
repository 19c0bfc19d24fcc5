"""Finding M3 of issue 33: work and memory are bounded before a large body is validated.
A body of many bad items gets one error for its first bad item (a list is checked in one
pass before pydantic builds an error per item), and any 422 carries at most
``MAX_ERRORS`` errors with each echoed input cut short: before, a 300 KB
``{"wi": [[], [], ...]}`` answered an 18 MB 422 after 3-5 s and held up the event loop."""
from __future__ import annotations

import json

import pytest

from bsdflab.service.errors import MAX_ERRORS, MAX_INPUT_CHARS, bounded_errors
from support.service_client import make_client

DIFFUSE = {"type": "diffuse", "reflectance": 0.5}
N = 100_000


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    # containers allowed beyond N: the list checks below the bracket count are what is tested
    with make_client(tmp_path_factory.mktemp("bodies"), limit_body_bytes=4 << 20, limit_json_containers=1 << 18) as c:
        yield c


def _post(client, route, body):
    return client.post(route, content=json.dumps(body), headers={"content-type": "application/json"})


@pytest.mark.parametrize("route, body, where", [
    ("/v1/bsdf/eval", {"model": DIFFUSE, "wi": [[]] * N, "wo": [[0, 0, 1]]}, "item 0"),
    ("/v1/bsdf/eval", {"model": DIFFUSE, "wi": [[0, 0, 1]] * 7 + [[0, 0, True]] * N, "wo": [[0, 0, 1]]}, "item 7"),
    ("/v1/bsdf/eval", {"model": DIFFUSE, "theta_i": ["x"] * N, "theta_o": [0]}, "item 0"),
    ("/v1/thinfilm/spectrum", {"angles": [0.0, None] * N}, "item 1"),
    ("/v1/tables", {"model": DIFFUSE, "wavelengths": [False] * N}, "item 0"),
    ("/v1/bsdf/eval", {"model": DIFFUSE, "theta_i": [0], "theta_o": [0], **{f"x{i}": 0 for i in range(N)}},
     "unknown fields"),
])
def test_a_body_of_many_bad_items_gets_one_short_422(client, route, body, where):
    """Mutation caught: without the one-pass list checks (plain ``list[float]``) the
    first case answers N errors, about 18 MB; without ``Request._known_fields`` the
    unknown-field case answers N "extra inputs" errors (MB before the cap, no "unknown
    fields" after it)."""
    r = _post(client, route, body)
    assert r.status_code == 422, r.text[:500]
    errors = r.json()["detail"]
    assert len(errors) <= MAX_ERRORS and len(r.content) < 16 << 10, (len(errors), len(r.content))
    assert where in json.dumps(errors), errors


def test_the_422_cap_keeps_the_first_errors_and_says_how_many(client):
    """Several bad fields: each listed, each echoed input cut short; past MAX_ERRORS, the
    first ones and a count of the rest. Mutation caught: no cut of ``input`` lets the
    5000-character strings through."""
    long = "z" * 5000
    body = {"model": DIFFUSE, "theta_i": long, "theta_o": long, "samples": long, "seed": long}
    errors = _post(client, "/v1/bsdf/eval", body).json()["detail"]
    assert len(errors) == 4 and all(len(json.dumps(e["input"])) <= MAX_INPUT_CHARS + 8 for e in errors), errors
    many = [{"type": "x", "loc": ["body", i], "msg": "bad", "input": long} for i in range(100)]
    shown = bounded_errors(many)
    assert len(shown) == MAX_ERRORS and str(100 - MAX_ERRORS + 1) in shown[-1]["msg"]


def test_good_large_bodies_still_pass(client):
    """The checks refuse nothing valid: 500 vectors (the test limit) evaluate."""
    body = {"model": DIFFUSE, "wi": [[0, 0, 1]] * 500, "wo": [[0.6, 0, 0.8]] * 500}
    r = _post(client, "/v1/bsdf/eval", body)
    assert r.status_code == 200 and len(r.json()["values"]) == 500


def test_a_body_of_too_many_arrays_is_refused_before_parsing(tmp_path):
    """Counted, not parsed: 2000 empty lists against a limit of 1000. Mutation caught: no
    count, and the body reaches the parser (the 422 then names item 0, not the limit)."""
    with make_client(tmp_path, limit_json_containers=1000) as client:
        r = _post(client, "/v1/bsdf/eval", {"model": DIFFUSE, "wi": [[]] * 2000, "wo": [[0, 0, 1]]})
        assert r.status_code == 422 and "BSDFLAB_LIMIT_JSON_CONTAINERS" in r.text
        assert _post(client, "/v1/bsdf/eval", {"model": DIFFUSE, "wi": [[0, 0, 1]] * 400,
                                               "wo": [[0, 0, 1]]}).status_code == 200


@pytest.mark.parametrize("route, body", [
    ("/v1/bsdf/eval", {"model": {"type": "roughconductor", "material": "m" * 100_000}, "theta_i": [0], "theta_o": [0]}),
    ("/v1/renders", {"scene": "s" * 100_000}),
    ("/v1/tables", {"model": DIFFUSE, "grid": {"g" * 100_000: 1}}),
])
def test_a_python_api_message_quoting_the_input_is_cut(client, route, body):
    """The Python API's ValueError quotes a bad name whole ("unknown metal '<100 KB>'"):
    the 422 echoed the body's size back. Mutation caught: ``str(exc)`` uncut (100 KB)."""
    r = _post(client, route, body)
    assert r.status_code == 422 and len(r.content) < 2000, (r.status_code, len(r.content))
