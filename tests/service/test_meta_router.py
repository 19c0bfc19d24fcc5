"""Catalogues, /v1/version, /healthz, the page and its files, the single admin key."""
from __future__ import annotations

import pytest

from bsdflab import presets
from bsdflab.scenes import SCENES
from support.service_client import DIFFUSE, TINY_TABLE, make_client


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("meta")) as c:
        yield c


def test_presets_scenes_version(client):
    listed = client.get("/v1/presets").json()
    assert [p["name"] for p in listed] == list(presets.PRESETS)
    assert listed[0]["model"] == presets.xenopeltis().to_dict()
    assert listed[0]["parameters"]["film_thickness_nm"] == presets.FILM_THICKNESS_NM
    assert [s["name"] for s in client.get("/v1/scenes").json()] == list(SCENES)
    version = client.get("/v1/version").json()
    assert version["bsdflab"] and version["limits"]["directions"] == 500 and not version["api_key_required"]
    assert client.get("/healthz").json() == {"status": "ok"}
    assert client.get("/docs").status_code == 200 and "/v1/tables" in client.get("/openapi.json").json()["paths"]


def test_page_and_plotly_are_served(client):
    page = client.get("/")
    assert page.status_code == 200 and "/vendor/plotly.min.js" in page.text
    js = client.get("/vendor/plotly.min.js")
    assert js.status_code == 200 and len(js.content) > 1_000_000
    assert client.get("/static/app.js").status_code == 200


def test_api_key_guards_work_and_deletes(tmp_path):
    with make_client(tmp_path, api_key="s3cret") as c:
        body = {"model": DIFFUSE, "theta_i": [0], "theta_o": [0]}
        assert c.post("/v1/bsdf/eval", json=body).status_code == 401
        assert c.post("/v1/bsdf/eval", json=body, headers={"X-API-Key": "wrong"}).status_code == 401
        assert c.post("/v1/bsdf/eval", json=body, headers={"X-API-Key": "s3cret"}).status_code == 200
        assert c.post("/v1/bsdf/eval", json=body, headers={"Authorization": "Bearer s3cret"}).status_code == 200
        assert c.post("/v1/tables", json=TINY_TABLE).status_code == 401
        assert c.delete(f"/v1/jobs/{'0' * 32}").status_code == 401
        assert c.get("/v1/presets").status_code == 401 and c.get("/healthz").status_code == 200
        assert c.get("/v1/version", headers={"X-API-Key": "s3cret"}).json()["api_key_required"]


def test_the_api_docs_load_nothing_from_a_cdn(client):
    """Before: /docs and /redoc loaded Swagger UI and ReDoc from a CDN (blank offline,
    unpinned). Now every script and stylesheet they name is served here, from the
    fastapi-offline wheel. Mutation caught: FastAPI's default docs (a cdn.jsdelivr.net URL)."""
    import re

    for page in ("/docs", "/redoc"):
        html = client.get(page).text
        urls = re.findall(r'(?:src|href)=["\']([^"\']+)["\']', html) + re.findall(r'url: ["\']([^"\']+)', html)
        assert urls and not [u for u in urls if u.startswith(("http:", "https:", "//"))], (page, urls)
        for url in urls:
            if url.startswith("/vendor/"):
                r = client.get(url)
                assert r.status_code == 200 and len(r.content) > 1000, url
