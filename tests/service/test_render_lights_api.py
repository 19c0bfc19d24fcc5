"""Lights in render requests (POST /v1/renders "lights"): a bad light is a 422 naming its
field, a good one reaches the job's normalised request, and a request without lights keeps
the key it had before lights existed."""
from __future__ import annotations

import pytest

from bsdflab.jobs import render as render_job
from support.service_client import detail, make_client


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("render-lights")) as c:
        yield c


BASE = {"scene": "furnace", "width": 8, "height": 8, "spp": 1}


@pytest.mark.parametrize("light, words", [
    ({"type": "point", "position": [0, 1, 0], "intensity": -1}, "intensity"),
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 1, "cutoff_angle_deg": 0},
     "cutoff_angle_deg"),
    ({"type": "directional", "direction": [0, 0, 0], "irradiance": 1}, "direction"),
    ({"type": "sun", "turbidity": "clear"}, "turbidity"),
    ({"type": "torch"}, "unknown light type"),
])
def test_bad_lights_are_422(client, light, words):
    r = client.post("/v1/renders", json={**BASE, "lights": [light]})
    assert r.status_code == 422 and words in detail(r), r.text


def test_a_light_reaches_the_render_request(client):
    light = {"type": "point", "position": [0, 3, 0], "intensity": 2.0}
    r = client.post("/v1/renders", json={**BASE, "lights": [light]})
    assert r.status_code in (200, 202), r.text
    render = r.json() if r.status_code == 200 else client.get(r.json()["links"]["artefact"]).json()
    assert render["request"]["lights"] == [{"type": "point", "position": [0.0, 3.0, 0.0], "intensity": [2.0, 2.0, 2.0]}]


def test_requests_without_lights_keep_their_key():
    plain = render_job.normalise({**BASE, "lights": None})
    assert "lights" not in plain
    assert render_job.key(plain) == render_job.key(render_job.normalise(dict(BASE)))
    lit = render_job.normalise({**BASE, "lights": [{"type": "sun"}]})
    assert render_job.key(lit) != render_job.key(plain)
    assert render_job.build_scene(lit).lights[0].type == "sun"
