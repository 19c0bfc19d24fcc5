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
