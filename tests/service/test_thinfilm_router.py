"""/v1/thinfilm through TestClient: the spectra equal bsdflab.optics."""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab.optics import film_reflectance, film_transmittance
from bsdflab.plots.film_colour import spectral_rgb
from support.service_client import detail, make_client


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("thinfilm")) as c:
        yield c


def test_thinfilm_spectrum_equals_the_optics(client):
    body = {"film_ior": 1.6, "thickness_nm": 300, "angles": [0, 40, 70], "wavelengths": [400, 500, 600, 700]}
    out = client.post("/v1/thinfilm/spectrum", json=body).json()
    film = (1.000277, 1.6, 300.0, 1.5515)
    theta = np.radians([0, 40, 70])[:, None]
    np.testing.assert_allclose(out["reflectance"], film_reflectance(film, np.array([400, 500, 600, 700.0]), theta),
                               rtol=1e-12)
    np.testing.assert_allclose(out["transmittance"], film_transmittance(film, np.array([400, 500, 600, 700.0]), theta),
                               rtol=1e-12)
    np.testing.assert_allclose(out["rgb"], spectral_rgb(film, np.radians([0, 40, 70])), rtol=1e-12)
    assert all(len(c) == 7 and c[0] == "#" for c in out["srgb"])
    r = client.post("/v1/thinfilm/spectrum", json={"angles": [100]})
    assert r.status_code == 422 and "angles" in detail(r)
    assert client.post("/v1/thinfilm/spectrum", json={"film_ior": -1}).status_code == 422
    # found by the long schemathesis run: a tiny index gave NaN spectra (a 200 with nulls)
    r = client.post("/v1/thinfilm/spectrum", json={"film_ior": 2.632460067801165e-162})
    assert r.status_code == 422 and "film_ior" in detail(r)


def test_a_film_stack_equals_the_quarter_wave_formula(client):
    """``layers`` (top first): a stack of N quarter-wave pairs (HL)^N on a substrate reflects,
    at normal incidence and the design wavelength, R = ((n0 - Y) / (n0 + Y))^2 with
    Y = (nH / nL)^(2N) ns (each quarter-wave layer maps the admittance below it to
    n^2 / Y; Macleod, Thin-Film Optical Filters, ch. 2). Mutation caught: ignoring
    ``layers`` (the one default film answers)."""
    n0, nh, nl, ns, design = 1.0, 2.3, 1.38, 1.52, 550.0
    for pairs in (1, 3):
        layers = [{"ior": n, "thickness_nm": design / (4 * n)} for _ in range(pairs) for n in (nh, nl)]
        body = {"ext_ior": n0, "substrate_ior": ns, "layers": layers, "angles": [0.0], "wavelengths": [design]}
        r = client.post("/v1/thinfilm/spectrum", json=body)
        assert r.status_code == 200, r.text
        y = (nh / nl) ** (2 * pairs) * ns
        np.testing.assert_allclose(r.json()["reflectance"][0][0], ((n0 - y) / (n0 + y)) ** 2, rtol=1e-9, atol=0)
        np.testing.assert_allclose(r.json()["transmittance"][0][0], 1 - ((n0 - y) / (n0 + y)) ** 2, rtol=1e-9)


@pytest.mark.parametrize("body, words", [
    ({"layers": []}, "layers"),
    ({"layers": [{"ior": 1.5, "thickness_nm": 100}], "film_ior": 1.6}, "layers"),
    ({"layers": [{"ior": 1.5, "thickness_nm": -1}]}, "thickness_nm"),
    ({"layers": [{"ior": 1.5, "thickness_nm": 100}] * 65}, "layers"),
])
def test_bad_film_stacks_are_422(client, body, words):
    r = client.post("/v1/thinfilm/spectrum", json=body)
    assert r.status_code == 422 and words in r.text, r.text
