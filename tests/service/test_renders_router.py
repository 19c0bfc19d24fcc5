"""/v1/renders through TestClient: options are checked at submission (the worker's own
checks, run before the job is queued), limits, missing renders."""
from __future__ import annotations

import pytest

from support.service_client import detail, make_client


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("renders")) as c:
        yield c


@pytest.mark.parametrize("options, words", [
    ({"reflectance": -1}, "reflectance"),
    ({"subdivisions": 10**9}, "subdivisions"),
    ({"colour": "red"}, "colour"),
])
def test_bad_options_are_422_at_submission(client, options, words):
    """Before: reflectance -1 and 10^9 subdivisions were accepted with 202 and failed in the worker."""
    r = client.post("/v1/renders", json={"scene": "furnace", "options": options, "width": 8, "height": 8, "spp": 1})
    assert r.status_code == 422 and words in detail(r), r.text
    assert client.get("/v1/jobs").json()["jobs"] == []


def test_missing_renders_are_404(client):
    missing = "0" * 64
    assert client.get(f"/v1/renders/{missing}").status_code == 404
    assert client.get(f"/v1/renders/{missing}/image.png").status_code == 404
    assert client.get(f"/v1/renders/{missing}/image.exr").status_code == 404
