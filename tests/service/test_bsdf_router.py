"""/v1/bsdf through TestClient: answers equal the Python API's, errors are 4xx naming the
problem, answers are bounded before computing and have a binary form."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest

from bsdflab import presets
from bsdflab.slices import directions_from_angles, evaluate, hemisphere, plane_of_incidence
from support.service_client import DIFFUSE, detail, make_client


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("bsdf")) as c:
        yield c


def test_eval_diffuse_is_the_closed_form(client):
    """Lambert: f cos = R cos(theta_o) / pi; angles and vectors give the same pairs."""
    body = {"model": DIFFUSE, "theta_i": [0, 30, 60], "theta_o": [10, 45, 80], "phi": [180]}
    r = client.post("/v1/bsdf/eval", json=body)
    assert r.status_code == 200, r.text
    out = r.json()
    expected = 0.5 * np.cos(np.radians([10, 45, 80])) / np.pi
    np.testing.assert_allclose(np.asarray(out["values"]), np.repeat(expected[:, None], 3, axis=1), rtol=1e-12)
    assert out["stderr"] is None and not out["stochastic"] and out["channels"] == ["R", "G", "B"]
    wi, wo = directions_from_angles([0, 30, 60], [10, 45, 80], [180])
    by_vector = client.post("/v1/bsdf/eval", json={"model": DIFFUSE, "wi": wi.tolist(), "wo": wo.tolist()}).json()
    np.testing.assert_array_equal(by_vector["values"], out["values"])


def test_eval_layered_equals_the_python_api_and_repeats(client):
    body = {"preset": "xenopeltis", "overrides": {"film_thickness_nm": 500.0}, "theta_i": [20],
            "theta_o": [20, 40], "samples": 64, "seed": 3, "wavelengths": [450, 550, 650]}
    first, second = (client.post("/v1/bsdf/eval", json=body).json() for _ in range(2))
    assert first == second and first["stochastic"] and first["channels"] == ["450", "550", "650"]
    wi, wo = directions_from_angles([20], [20, 40], [180])
    direct = evaluate(presets.xenopeltis(film_thickness_nm=500.0), wi, wo, [450, 550, 650], 64, 3)
    np.testing.assert_array_equal(first["values"], direct.values)
    np.testing.assert_array_equal(first["stderr"], direct.stderr)


@pytest.mark.parametrize("body, status, words", [
    ({"preset": "nope", "theta_i": [0], "theta_o": [0]}, 422, "unknown preset 'nope'"),
    ({"model": DIFFUSE, "preset": "xenopeltis", "theta_i": [0], "theta_o": [0]}, 422, "exactly one"),
    ({"model": {"type": "diffuse", "reflectance": 2}, "theta_i": [0], "theta_o": [0]}, 422, "reflectance"),
    ({"model": DIFFUSE, "wi": [[0, 0, 2]], "wo": [[0, 0, 1]]}, 422, "wi must be unit vectors"),
    ({"model": DIFFUSE, "theta_i": [95], "theta_o": [0]}, 422, "theta_i must be <= 90"),
    ({"model": DIFFUSE, "wi": [[0, 0, 1]], "theta_o": [0]}, 422, "either as vectors"),
    ({"model": DIFFUSE, "theta_i": [0] * 501, "theta_o": [0]}, 422, "BSDFLAB_LIMIT_DIRECTIONS"),
    ({"model": DIFFUSE, "theta_i": [0], "theta_o": [0], "colour": 1}, 422, "colour"),
    ({"preset": "xenopeltis", "overrides": {"thickness": 1}, "theta_i": [0], "theta_o": [0]}, 422, "thickness"),
    ({"preset": "xenopeltis", "theta_i": [0], "theta_o": [0], "samples": 100_000}, 422, "BSDFLAB_LIMIT_SAMPLES"),
    ({"model": DIFFUSE, "theta_i": [0], "theta_o": [0], "seed": -1}, 422, "seed"),
])
def test_eval_errors_are_422_with_a_message(client, body, status, words):
    r = client.post("/v1/bsdf/eval", json=body)
    assert r.status_code == status and words in detail(r), r.text


def test_malformed_and_oversized_bodies(client):
    r = client.post("/v1/bsdf/eval", content=b"{not json", headers={"content-type": "application/json"})
    assert r.status_code == 422
    r = client.post("/v1/bsdf/eval", content=b"[" + b"0," * 40_000 + b"0]",
                    headers={"content-type": "application/json"})
    assert r.status_code == 413 and "BSDFLAB_LIMIT_BODY_BYTES" in r.text


def test_lobe_views_equal_the_python_api(client):
    r = client.post("/v1/bsdf/lobe", json={"model": DIFFUSE, "theta_i": 30, "points": 7, "resolution": 9})
    assert r.status_code == 200, r.text
    out = r.json()
    angles, v = plane_of_incidence(presets.xenopeltis_diffuse(base_albedo=0.5), 30, 7)
    np.testing.assert_array_equal(out["plane"]["angle_deg"], angles)
    np.testing.assert_allclose(np.asarray(out["plane"]["values"])[:, 0], 0.5 * np.cos(np.radians(angles)) / np.pi,
                               rtol=1e-12, atol=1e-15)
    x, inside, hv = hemisphere(presets.xenopeltis_diffuse(base_albedo=0.5), 30, 9)
    lum = np.asarray([[np.nan if c is None else c for c in row] for row in out["hemisphere"]["luminance"]])
    assert np.array_equal(~np.isnan(lum), inside)
    np.testing.assert_allclose(lum[inside], hv.values @ [0.2126, 0.7152, 0.0722], rtol=1e-12)
    assert not out["stochastic"] and out["hemisphere"]["luminance_stderr"] is None


def test_lobe_png_and_its_errors(client):
    r = client.get("/v1/bsdf/lobe.png", params={"model": json.dumps(DIFFUSE), "theta_i": 20, "samples": 2000})
    assert r.status_code == 200 and r.content[:8] == b"\x89PNG\r\n\x1a\n"
    assert client.get("/v1/bsdf/lobe.png", params={"model": "{oops"}).status_code == 422
    r = client.post("/v1/bsdf/lobe.png", json={"model": DIFFUSE, "theta_i": 90})
    assert r.status_code == 422 and "theta_i" in detail(r)
    r = client.post("/v1/bsdf/lobe", json={"model": DIFFUSE, "points": 10_000})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_LOBE_RESOLUTION" in detail(r)


# -- answers bounded before computing, and their binary form ------------------------------
@pytest.fixture(scope="module")
def wide(tmp_path_factory):
    """The default direction limit and room for a large request body."""
    with make_client(tmp_path_factory.mktemp("wide"), limit_body_bytes=1 << 20, limit_directions=100_000) as c:
        yield c


def test_pairs_times_channels_is_capped_before_computing(wide):
    """Before: 20 000 pairs x 1 024 wavelengths of a diffuse model (a 164 KB request) was
    answered with 408 MB of JSON."""
    body = {"model": DIFFUSE, "theta_i": [30.0], "theta_o": list(np.linspace(0, 80, 20_000)),
            "wavelengths": list(np.linspace(380, 780, 1024))}
    r = wide.post("/v1/bsdf/eval", json=body)
    assert r.status_code == 422 and "BSDFLAB_LIMIT_RESPONSE_BYTES" in r.text and "20000 pairs x 1024" in r.text
    r = wide.post("/v1/bsdf/eval", json=body, headers={"Accept": "application/x-npy"})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_RESPONSE_BYTES" in r.text


def test_lobe_grids_are_capped(tmp_path):
    with make_client(tmp_path, limit_response_bytes=1 << 20) as c:
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


FILMED = {"type": "roughconductor", "alpha": 0.3, "material": "Au", "film": [{"material": 1.5, "thickness_nm": 400}]}


def test_a_film_thickness_per_query(client):
    """``thickness_nm`` (one per pair, or one) replaces the film's thickness for that query:
    equal to the model made with that thickness, evaluated alone. Mutation caught: ignoring
    the field (both rows answer the 400 nm film)."""
    angles = {"theta_i": [30, 30], "theta_o": [30, 40], "phi": [180, 180], "wavelengths": [500.0, 600.0]}
    r = client.post("/v1/bsdf/eval", json={"model": FILMED, **angles, "thickness_nm": [300.0, 500.0]})
    assert r.status_code == 200, r.text
    got = np.array(r.json()["values"])
    for row, t in enumerate((300.0, 500.0)):
        alone = {**FILMED, "film": [{"material": 1.5, "thickness_nm": t}]}
        one = {k: [v[row]] if isinstance(v, list) and k != "wavelengths" else v for k, v in angles.items()}
        want = np.array(client.post("/v1/bsdf/eval", json={"model": alone, **one}).json()["values"])
        np.testing.assert_allclose(got[row], want[0], rtol=1e-12, atol=0)
    for bad in ([300.0, 500.0, 700.0], [-1.0]):
        r = client.post("/v1/bsdf/eval", json={"model": FILMED, **angles, "thickness_nm": bad})
        assert r.status_code == 422 and "thickness" in r.text, r.text
