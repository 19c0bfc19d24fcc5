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


def test_a_render_is_sized_not_built_before_admission(tmp_path, monkeypatch):
    """Finding M8 of issue 33: a render's mesh was built in the web process before the
    queue check (furnace subdivisions 2048: 1.4 s and +612 MB, paid even when the 429
    followed). Now its size is estimated (the builder stops at its size check) and only the
    worker builds it. Mutation caught: ``build_mesh`` in render_checks again (the request
    thread builds a grid)."""
    import threading

    from bsdflab.render import geometry

    built_by = []
    real = geometry.grid_indices

    def counted(*args, **kwargs):
        built_by.append(threading.current_thread().name)
        return real(*args, **kwargs)

    monkeypatch.setattr(geometry, "grid_indices", counted)
    with make_client(tmp_path, limit_queue=1) as client:
        body = {"scene": "furnace", "options": {"subdivisions": 2048}, "width": 4, "height": 4, "spp": 1}
        first = client.post("/v1/renders", json=body)
        assert first.status_code == 202, first.text
        full = client.post("/v1/renders", json={**body, "seed": 1})
        assert full.status_code == 429
        bad = client.post("/v1/renders", json={**body, "options": {"subdivisions": 10 ** 9}})
        assert bad.status_code == 422 and "subdivisions" in bad.text
        client.delete(f"/v1/jobs/{first.json()['id']}")
    assert not [name for name in built_by if not name.startswith("bsdflab-job")], built_by
