"""Findings M1, M2 and M4 of issue 33, and the measured uploads' minor ones: a stored file
named by hash is accepted only where a model goes and is never turned into a server path
in a request, an error or a table file; hash references are resolved on the heavy pool,
after its admission; an upload that cannot be tabulated is refused at submission."""
from __future__ import annotations

import numpy as np
import pytest
from fastapi.testclient import TestClient

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import export_model
from bsdflab.measured.merl import DIMS, merl_bytes
from bsdflab.service import Settings, create_app
from bsdflab.tables import read_attributes

ANGLES = {"theta_i": [0, 30], "theta_o": [10, 40]}
GRID = {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    settings = Settings(data_dir=(folder := tmp_path_factory.mktemp("refs-data")), cache_dir=folder / "tables",
                        executor="threads", workers=1,
                        progress_interval_s=0.05)
    with TestClient(create_app(settings)) as c:
        yield c


@pytest.fixture(scope="module")
def hashes(client, tmp_path_factory):
    """Uploaded: an RGB RGL file, a spectral one and a MERL file."""
    folder = tmp_path_factory.mktemp("refs-files")
    cu = RoughConductor(alpha=0.2, material="Cu")
    export_model(cu, folder / "rgb.bsdf", n_theta_i=4, resolution=8, error_points=100)
    export_model(cu, folder / "s.bsdf", wavelengths=[450.0, 550.0, 650.0], n_theta_i=4, resolution=8,
                 error_points=100)
    (folder / "m.binary").write_bytes(merl_bytes(0.01 + 0.5 * np.random.default_rng(3).random((3, *DIMS))))
    found = {}
    for name, fmt, file in (("rgb", "rgl", "rgb.bsdf"), ("spectral", "rgl", "s.bsdf"), ("merl", "merl", "m.binary")):
        r = client.post("/v1/measured", params={"format": fmt}, content=(folder / file).read_bytes(),
                        headers={"content-type": "application/octet-stream"})
        assert r.status_code == 200, r.text
        found[name] = r.json()["hash"]
    return found


def _misplaced(ref):
    # a render's options.material is a model's place (tests/service/test_render_material.py); a
    # parameter of the material's model is not
    material = {"type": "tabulated", "model": {"type": "diffuse", "reflectance": ref}}
    return [("/v1/renders", {"scene": "sphere", "options": {"material": material}, "width": 4, "height": 4,
                             "spp": 1}),
            ("/v1/renders", {"scene": "sphere", "options": {"variant": ref}, "width": 4, "height": 4, "spp": 1}),
            ("/v1/bsdf/eval", {"model": {"type": "roughconductor", "alpha": ref}, **ANGLES}),
            ("/v1/bsdf/eval", {"preset": "xenopeltis", "overrides": {"film_thickness_nm": ref}, **ANGLES}),
            ("/v1/tables", {"model": {"type": "diffuse", "reflectance": ref}, "grid": GRID})]


@pytest.mark.parametrize("which", ["rgb", "merl"])
def test_a_hash_where_no_model_goes_is_refused_without_a_path(client, hashes, which):
    """Before: the reference was resolved to its store path and the 422 echoed the path.
    Mutation caught: resolving references at any depth (the old walk) puts the data
    folder in the 422s."""
    data_dir = str(client.app.state.settings.data_dir)
    ref = {"type": "measured" if which == "rgb" else "merl", "hash": hashes[which]}
    for route, body in _misplaced(ref):
        r = client.post(route, json=body)
        assert r.status_code == 422, (route, body, r.text)
        assert data_dir not in r.text and "/artefacts" not in r.text, r.text
        assert "only where a model goes" in r.text, r.text


def test_a_hash_where_a_model_goes_still_works(client, hashes):
    for ref in ({"type": "measured", "hash": hashes["rgb"]}, {"type": "merl", "hash": hashes["merl"]}):
        assert client.post("/v1/bsdf/eval", json={"model": ref, **ANGLES}).status_code == 200
    layered = {"type": "layered", "interfaces": [{"type": "dielectric", "int_ior": 1.5}],
               "slabs": [{"thickness_nm": 0}], "base": {"type": "measured", "hash": hashes["rgb"]}, "samples": 8}
    r = client.post("/v1/bsdf/eval", json={"model": layered, **ANGLES})
    assert r.status_code in (200, 422) and str(client.app.state.settings.data_dir) not in r.text


def test_the_table_file_of_an_upload_names_it_by_hash(client, hashes, tmp_path):
    """Before: the EXR's ``bsdflab.model`` attribute held the upload's server path.
    Mutation caught: resolving the hash to a path in the request again."""
    job = client.post("/v1/tables", json={"model": {"type": "measured", "hash": hashes["spectral"]},
                                          "wavelengths": [450.0, 550.0, 650.0], "grid": GRID}).json()
    while job["state"] not in ("done", "failed", "cancelled"):
        job = client.get(f"/v1/jobs/{job['id']}").json()
    assert job["state"] == "done", job
    (tmp_path / "t.exr").write_bytes(client.get(f"/v1/tables/{job['hash']}/file").content)
    model = read_attributes(tmp_path / "t.exr")["bsdflab.model"]
    assert hashes["spectral"] in model and str(client.app.state.settings.data_dir) not in model


@pytest.mark.parametrize("which, body", [("rgb", {"wavelengths": [450.0, 550.0, 650.0]}), ("rgb", {}),
                                         ("merl", {})])
def test_an_upload_that_cannot_be_tabulated_is_422_at_submission(client, hashes, which, body):
    """A table is made from spectra; an RGB-only file (MERL, RGB RGL) cannot give them.
    Before: accepted with 202, then the job failed in the worker ("P must have ...").
    Mutation caught: no ``_check_spectral`` at submission (202)."""
    model = {"type": "measured" if which == "rgb" else "merl", "hash": hashes[which]}
    r = client.post("/v1/tables", json={"model": model, "grid": GRID, **body})
    assert r.status_code == 422 and "RGB only" in r.text, r.text


def test_references_are_resolved_after_the_heavy_pools_admission(client):
    """Before: references were looked up on the event loop before the pool's 429 (8
    clients of 45 000 references held /healthz for seconds). With every slot taken, an
    unknown hash is now a 429 (not looked up), and the lookups run on the pool. Mutation
    caught: ``model_spec`` called before ``heavy.run`` answers the 422 "no table"."""
    heavy = client.app.state.heavy
    heavy.in_flight += heavy.size
    try:
        for route in ("/v1/bsdf/eval", "/v1/bsdf/lobe", "/v1/bsdf/lobe.png"):
            r = client.post(route, json={"model": {"type": "table", "hash": "0" * 64}, **(
                ANGLES if route.endswith("eval") else {})})
            assert r.status_code == 429, (route, r.text)
    finally:
        heavy.in_flight -= heavy.size


def test_references_per_request_are_capped(client, hashes):
    """Mutation caught: no count (the 17 references are each looked up: 200 or a model error)."""
    ref = {"type": "measured", "hash": hashes["rgb"]}
    layered = {"type": "layered", "interfaces": [ref] * 17, "slabs": [{}] * 17, "base": ref}
    r = client.post("/v1/bsdf/eval", json={"model": layered, **ANGLES})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_STORE_REFS" in r.text, r.text


def test_the_model_cache_is_bounded_by_bytes(tmp_path):
    """Finding M9: measured models (about 51 MB each for MERL) were kept 32 at a time
    whatever their size. With a bound of 2.5 files' worth, three different uploads leave
    at most two models kept. Mutation caught: evicting by count only (all three kept)."""
    from bsdflab.requests import ModelCache, model_bytes
    from bsdflab.service.routers.bsdf import MODELS

    folder = tmp_path / "files"
    folder.mkdir()
    specs = []
    for i, alpha in enumerate((0.2, 0.3, 0.4)):
        export_model(RoughConductor(alpha=alpha, material="Cu"), folder / f"{i}.bsdf", n_theta_i=4, resolution=8,
                     error_points=100)
        specs.append({"model": {"type": "measured", "path": str(folder / f"{i}.bsdf")}})
    one = model_bytes(ModelCache().get(specs[0]))
    cache = ModelCache(32, max_bytes=int(2.5 * one))
    for spec in specs:
        cache.get(spec)
    assert len(cache) == 2 and cache.bytes <= 2.5 * one
    assert one > 2 * (folder / "0.bsdf").stat().st_size   # the file counted twice, and the model's overhead
    settings = Settings(data_dir=tmp_path / "d", cache_dir=tmp_path / "tables",
                        executor="threads", workers=1, model_cache_bytes=12345)
    with TestClient(create_app(settings)):
        assert MODELS.max_bytes == 12345
