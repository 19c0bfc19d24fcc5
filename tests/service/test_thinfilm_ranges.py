"""/v1/thinfilm accepts the physical ranges the library accepts (bsdflab/util/ranges.py):
before issue 34 the route kept its own, narrower copies (films up to 1e7 nm, wavelengths up
to 1e6 nm) while bsdflab.optics took 1e9 nm and 1e12 nm."""

from __future__ import annotations

import numpy as np
import pytest

from bsdflab.optics import film_reflectance
from bsdflab.service.routers import thinfilm
from bsdflab.util import args as check
from bsdflab.util import ranges
from support.service_client import detail, make_client


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("thinfilm_ranges")) as c:
        yield c


def test_the_routes_ranges_are_the_librarys():
    assert thinfilm.IOR_RANGE == (check.MIN_IOR, check.MAX_IOR) == ranges.IOR_RANGE
    assert thinfilm.WAVELENGTH_RANGE_NM == (check.MIN_WAVELENGTH_NM, check.MAX_WAVELENGTH_NM)
    assert thinfilm.MAX_THICKNESS_NM == check.MAX_FILM_THICKNESS_NM == ranges.MAX_FILM_THICKNESS_NM


def test_a_wavelength_the_library_takes_the_route_takes(client):
    """1e7 nm (a radio-ish wavelength: the film's phase vanishes, R is the bare stack's) was
    a 422 from the route's own 1e6 nm limit; past the library's 1e12 nm it still is."""
    body = {"film_ior": 1.6, "thickness_nm": 300, "angles": [0.0]}
    inside = ranges.MAX_WAVELENGTH_NM / 1e5
    r = client.post("/v1/thinfilm/spectrum", json={**body, "wavelengths": [inside]})
    assert r.status_code == 200, r.text
    expected = film_reflectance((1.000277, 1.6, 300.0, 1.5515), np.array([inside]), np.array([[0.0]]))
    np.testing.assert_allclose(r.json()["reflectance"], expected, rtol=1e-12)
    r = client.post("/v1/thinfilm/spectrum", json={**body, "wavelengths": [2 * ranges.MAX_WAVELENGTH_NM]})
    assert r.status_code == 422 and "wavelengths" in detail(r)


def test_a_thickness_past_the_librarys_range_names_it(client):
    """Past 1e9 nm the route answers with the range of thickness_nm; within it, a film
    too thick for the colour strip is refused by the strip (its own message)."""
    r = client.post("/v1/thinfilm/spectrum", json={"film_ior": 1.6, "thickness_nm": 2 * ranges.MAX_FILM_THICKNESS_NM})
    assert r.status_code == 422 and "thickness_nm" in detail(r) and "<= 1000000000.0" in detail(r)
    r = client.post("/v1/thinfilm/spectrum", json={"film_ior": 1.6, "thickness_nm": ranges.MAX_FILM_THICKNESS_NM / 10})
    assert r.status_code == 422 and "optical thickness" in detail(r)
