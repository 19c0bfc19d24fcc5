"""Issue 33, item 4, over HTTP (TestClient, jobs on threads): a render's ``options.material``
takes any material -- a BSDF dict, a preset and overrides, a tabulated one of either, a
stored table or measured file named by hash -- and a bad one is a 422 naming the field; no
response names a server path; a render's tables come from the one table cache that table
jobs fill, and its summary says which were reused."""
from __future__ import annotations

import json

import pytest

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import export_model
from support.service_client import detail, make_client, wait_job

DIFFUSE = {"type": "diffuse", "reflectance": [0.6, 0.3, 0.2]}
GRID = {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}
TINY = {"scene": "sphere", "width": 4, "height": 4, "spp": 1}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("render-material"), limit_queue=64) as c:
        yield c


def no_path(client, response) -> None:
    settings = client.app.state.settings
    for folder in (settings.data_dir, settings.cache_dir):
        assert str(folder) not in response.text, response.text
    assert "/artefacts" not in response.text and "/tables/" not in response.text.replace("/v1/tables/", ""), \
        response.text


def render(client, material, variant="diffuse", **extra):
    body = {**TINY, "options": {"variant": variant, "material": material}, **extra}
    return client.post("/v1/renders", json=body)


def cancel(client, response) -> None:
    if response.status_code == 202:
        client.delete(f"/v1/jobs/{response.json()['id']}")


@pytest.fixture(scope="module")
def table_hash(client):
    job = client.post("/v1/tables", json={"model": DIFFUSE, "grid": GRID}).json()
    assert wait_job(client, job["id"])["state"] == "done"
    return job["hash"]


@pytest.fixture(scope="module")
def measured_hash(client, tmp_path_factory):
    path = tmp_path_factory.mktemp("upload") / "cu.bsdf"
    export_model(RoughConductor(alpha=0.2, material="Cu"), path, wavelengths=[450.0, 550.0, 650.0], n_theta_i=4,
                 resolution=8, error_points=100)
    r = client.post("/v1/measured", params={"format": "rgl"}, content=path.read_bytes(),
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    return r.json()["hash"]


@pytest.mark.parametrize("material", [
    DIFFUSE,
    {"preset": "xenopeltis-diffuse"},
    {"preset": "xenopeltis", "overrides": {"film_thickness_nm": 520}},
    {"type": "tabulated", "model": DIFFUSE, "grid": GRID},
    {"type": "tabulated", "model": {"preset": "xenopeltis-thin-film", "overrides": {"film_thickness_nm": 300}},
     "grid": GRID, "method": "adding-doubling"},
    "table",
    "direct",
])
@pytest.mark.parametrize("scene", ["sphere", "torus", "snake"])
def test_each_material_form_is_accepted(client, material, scene):
    options = {"material": material} if scene == "snake" else {"variant": "full", "material": material}
    r = client.post("/v1/renders", json={**TINY, "scene": scene, "options": options})
    cancel(client, r)
    assert r.status_code in (200, 202), r.text
    info = client.get(f"/v1/renders/{r.json()['hash']}").json()
    assert info["request"]["options"]["material"] == material   # the material the request carried


@pytest.mark.parametrize("material, words", [
    ({"type": "diffuse", "reflectance": -1}, ["options.material", "reflectance"]),
    ({"type": "nonsense"}, ["options.material", "nonsense"]),
    ({"preset": "nope"}, ["options.material", "nope"]),
    ({"preset": "xenopeltis", "overrides": {"colour": 1}}, ["options.material", "colour"]),
    ({"preset": "xenopeltis", "model": DIFFUSE}, ["options.material", "model"]),
    ({"reflectance": 0.5}, ["options.material", "type"]),
    ({"type": "tabulated"}, ["options.material", "model"]),
    ({"type": "tabulated", "model": {"preset": "nope"}}, ["options.material.model", "nope"]),
    ({"type": "tabulated", "model": DIFFUSE, "grid": 3}, ["options.material", "grid"]),
    ({"type": "tabulated", "model": DIFFUSE, "rel_error": -1}, ["options.material", "rel_error"]),
    ({"type": "tabulated", "model": DIFFUSE, "method": "guess"}, ["options.material", "method"]),
    ({"type": "tabulated", "model": DIFFUSE, "wavelengths": [550]}, ["options.material", "wavelengths"]),
    (3, ["material"]),
    ("marble", ["material", "marble"]),
])
def test_a_bad_material_is_422_naming_the_field(client, material, words):
    before = len(client.get("/v1/jobs").json()["jobs"])
    r = render(client, material)
    assert r.status_code == 422, r.text
    for word in words:
        assert word in detail(r), (word, r.text)
    no_path(client, r)
    assert len(client.get("/v1/jobs").json()["jobs"]) == before   # nothing queued


def test_a_stored_table_by_hash_renders_and_is_shown_by_hash(client, table_hash):
    r = render(client, {"type": "table", "hash": table_hash}, variant="full")
    assert r.status_code in (200, 202), r.text
    no_path(client, r)
    if r.status_code == 202:
        assert wait_job(client, r.json()["id"])["state"] == "done"
    info = client.get(f"/v1/renders/{r.json()['hash']}")
    no_path(client, info)
    assert info.json()["request"]["options"]["material"] == {"type": "table", "hash": table_hash}
    assert client.get(info.json()["links"]["png"]).status_code == 200


def test_a_measured_file_by_hash_is_a_material(client, measured_hash):
    for material in ({"type": "measured", "hash": measured_hash},
                     {"type": "tabulated", "model": {"type": "measured", "hash": measured_hash}, "grid": GRID}):
        r = render(client, material)
        cancel(client, r)
        assert r.status_code in (200, 202), r.text
        no_path(client, r)
        assert client.get(f"/v1/renders/{r.json()['hash']}").json()["request"]["options"]["material"] == material


def test_a_stored_material_that_passed_its_check_is_not_checked_again(client, measured_hash):
    """The check of a render's stored materials is kept by its canonical JSON (the files are
    named by content hash): renders of the same material with other seeds send no second
    check to a worker. Mutation caught (run once): nothing kept (REMEMBERED empty: one
    more check per render)."""
    material = {"type": "measured", "hash": measured_hash}
    checker = client.app.state.jobs.checker
    first = render(client, material, seed=7001)
    cancel(client, first)
    assert first.status_code == 202, first.text
    sent = checker.submitted
    for seed in (7002, 7003):
        r = render(client, material, seed=seed)
        cancel(client, r)
        assert r.status_code == 202, r.text
    assert checker.submitted == sent


@pytest.fixture(scope="module")
def rgb_hash(client, tmp_path_factory):
    path = tmp_path_factory.mktemp("upload-rgb") / "cu-rgb.bsdf"
    export_model(RoughConductor(alpha=0.2, material="Cu"), path, n_theta_i=4, resolution=8, error_points=100)
    r = client.post("/v1/measured", params={"format": "rgl"}, content=path.read_bytes(),
                    headers={"content-type": "application/octet-stream"})
    assert r.status_code == 200 and not r.json()["summary"]["spectral"], r.text
    return r.json()["hash"]


@pytest.mark.parametrize("case, words", [
    ("rgb-tabulated", ["stores RGB, not spectra"]),
    ("layered-bad-interface", ["layered"]),
    ("adding-doubling-of-measured", ["adding-doubling", "Measured"]),
])
def test_a_material_naming_a_stored_file_is_checked_with_the_file_at_submission(client, measured_hash, rgb_hash,
                                                                                case, words):
    """A material naming a stored file was checked only for the file's existence at
    submission and failed as a job (each case: 202, then a failed render). Now it is built
    with the file loaded, in a check worker, before any job: 422 naming options.material,
    nothing queued. Mutation caught (run once): the route without the check (202)."""
    material = {
        "rgb-tabulated": {"type": "tabulated", "model": {"type": "measured", "hash": rgb_hash}, "grid": GRID},
        "layered-bad-interface": {"type": "layered", "base": {"type": "measured", "hash": measured_hash},
                                  "interfaces": [{"type": "nonsense"}]},
        "adding-doubling-of-measured": {"type": "tabulated", "model": {"type": "measured", "hash": measured_hash},
                                        "grid": GRID, "method": "adding-doubling"},
    }[case]
    before = len(client.get("/v1/jobs").json()["jobs"])
    r = render(client, material)
    assert r.status_code == 422, r.text
    for word in ["options.material", *words]:
        assert word in detail(r), (word, r.text)
    no_path(client, r)
    assert len(client.get("/v1/jobs").json()["jobs"]) == before


@pytest.mark.parametrize("where", ["variant", "overrides", "parameter"])
def test_a_hash_where_no_model_goes_is_refused_without_a_path(client, measured_hash, where):
    """Only the material itself (or a tabulated material's model) is a model's place."""
    ref = {"type": "measured", "hash": measured_hash}
    options = {"variant": ref, "material": DIFFUSE} if where == "variant" else {
        "material": {"preset": "xenopeltis", "overrides": {"film_thickness_nm": ref}} if where == "overrides"
        else {"type": "diffuse", "reflectance": ref}}
    r = client.post("/v1/renders", json={**TINY, "options": options})
    assert r.status_code == 422 and "only where a model goes" in r.text, r.text
    no_path(client, r)


@pytest.mark.parametrize("ref", [{"type": "table", "hash": "0" * 64}, {"type": "measured", "hash": "0" * 64},
                                 {"type": "table", "hash": "ABC"}, {"type": "table", "path": "/etc/passwd"}])
def test_an_unknown_or_malformed_reference_is_422_without_a_path(client, ref):
    r = render(client, ref)
    assert r.status_code == 422, r.text
    no_path(client, r)
    assert "/etc" not in r.text


def test_too_many_references_are_refused_before_any_lookup(client, table_hash):
    refs = [{"type": "table", "hash": table_hash}] * (client.app.state.settings.limit_store_refs + 1)
    material = {"type": "layered", "interfaces": refs, "base": DIFFUSE}
    r = render(client, material)
    assert r.status_code == 422 and "BSDFLAB_LIMIT_STORE_REFS" in r.text, r.text


@pytest.mark.parametrize("model", [DIFFUSE, {"type": "measured", "hash": None}])
def test_a_tabulated_materials_grid_is_held_to_the_table_cell_limit(client, measured_hash, model):
    """As a table job's (BSDFLAB_LIMIT_TABLE_CELLS, 50 000 here), also for a stored file's
    table. Mutation caught: render_checks without the cells (202, a 4.6 M-cell job)."""
    if model["type"] == "measured":
        model = {**model, "hash": measured_hash}
    grid = {"n_theta_i": 64, "n_theta_o": 128, "n_phi": 280}
    r = render(client, {"type": "tabulated", "model": model, "grid": grid})
    cancel(client, r)
    assert r.status_code == 422 and "BSDFLAB_LIMIT_TABLE_CELLS" in r.text, r.text
    no_path(client, r)


def test_a_render_reuses_the_table_a_table_job_made(client):
    """The table job and the render's tabulated material are one request (model, grid,
    target, method auto, RGB): one file in the one cache. The render's summary names it
    with from_cache true; a material the cache lacks is made (from_cache false) and then
    reused by the next render. Mutation caught: render jobs with a cache of their own (the
    artefact folder, as before): from_cache false for the table job's table."""
    model = {"type": "diffuse", "reflectance": [0.2, 0.7, 0.4]}
    job = client.post("/v1/tables", json={"model": model, "grid": GRID, "rel_error": 0.05}).json()
    assert wait_job(client, job["id"])["state"] == "done"
    material = {"type": "tabulated", "model": model, "grid": GRID, "rel_error": 0.05}
    first = _summary_tables(client, render(client, material))
    assert first == [{"hash": job["hash"], "method": first[0]["method"], "from_cache": True,
                      "target_met": first[0]["target_met"]}], first
    new = {**material, "model": {"type": "diffuse", "reflectance": [0.1, 0.1, 0.8]}}
    made = _summary_tables(client, render(client, new))
    again = _summary_tables(client, render(client, new, seed=1))
    assert [t["from_cache"] for t in made] == [False] and [t["from_cache"] for t in again] == [True]
    assert made[0]["hash"] == again[0]["hash"] and client.get(f"/v1/tables/{made[0]['hash']}").status_code == 200


def _summary_tables(client, r) -> list[dict]:
    assert r.status_code == 202, r.text
    assert wait_job(client, r.json()["id"])["state"] == "done"
    summary = client.get(f"/v1/renders/{r.json()['hash']}").json()["summary"]
    return json.loads(summary["tables"])
