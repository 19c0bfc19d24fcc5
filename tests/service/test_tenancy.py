"""Cross-tenant isolation of what is made from an upload: an adversarial review as tenant bob,
holding a valid key and alice's upload's hash (not its bytes). Each test of a finding failed
on the code before its fix (the before is in its docstring; mutations run once: without the
check in routers/renders.py, routers/tables.py or deps.py, the first or second test fails).
The last test is the design's other side: holding the bytes is holding the data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bsdflab.measured.rgl import write_rgl
from bsdflab.measured.rgl_file import RGLData
from support.service_client import make_client, wait_job

KEYS = {"alice": {"key": "a" * 32}, "bob": {"key": "b" * 32}, "ops": {"key": "o" * 32, "admin": True}}
ALICE, BOB, OPS = ({"X-API-Key": k * 32} for k in "abo")
OCTETS = {"content-type": "application/octet-stream"}
GRID = {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}
TINY = {"scene": "sphere", "width": 4, "height": 4, "spp": 1}
ABSENT = "0" * 64  # a hash nothing has: what "absent" answers
ANGLES = {"theta_i": [30.0], "theta_o": [30.0]}


def rgl_bytes(folder: Path, description: str = "alice's sample") -> bytes:
    """A small valid spectral RGL file (other bytes for another description)."""
    theta = np.linspace(0, 1.4, 2).astype(np.float32)
    data = RGLData(
        description=description,
        jacobian=True,
        theta_i=theta,
        phi_i=np.zeros(1, np.float32),
        ndf=np.ones((8, 8), np.float32),
        sigma=np.ones((8, 8), np.float32),
        vndf=np.ones((1, 2, 8, 8), np.float32),
        luminance=np.ones((1, 2, 8, 8), np.float32),
        values=np.full((1, 2, 4, 8, 8), 0.3, np.float32),
        wavelengths=np.linspace(380, 780, 4).astype(np.float32),
    )
    write_rgl(folder / "f.bsdf", data)
    return (folder / "f.bsdf").read_bytes()


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """One server; alice's upload, a table of it, renders of the upload, of a tabulated material
    and of the table, each done."""
    folder = tmp_path_factory.mktemp("tenancy")
    data = rgl_bytes(folder)
    with make_client(folder, api_keys=KEYS, limit_measured_bytes=8 << 20, limit_queue=8) as c:
        r = c.post("/v1/measured", params={"format": "rgl"}, content=data, headers={**ALICE, **OCTETS})
        assert r.status_code == 200, r.text
        ref = {"type": "measured", "hash": r.json()["hash"]}
        made = {}
        for name, path, body in (
            ("table", "/v1/tables", {"model": ref, "grid": GRID}),
            ("render", "/v1/renders", {**TINY, "options": {"material": ref}}),
            (
                "tabulated",
                "/v1/renders",
                {**TINY, "options": {"material": {"type": "tabulated", "model": ref, "grid": GRID}}},
            ),
        ):
            r = c.post(path, json=body, headers=ALICE)
            assert r.status_code == 202, r.text
            assert wait_job(c, r.json()["id"], timeout=300, headers=ALICE)["state"] == "done"
            made[name] = r.json()["hash"]
        # a render of the table by hash: its request holds the table's store path, not the upload
        r = c.post(
            "/v1/renders",
            json={**TINY, "options": {"material": {"type": "table", "hash": made["table"]}}},
            headers=ALICE,
        )
        assert r.status_code == 202 and wait_job(c, r.json()["id"], timeout=300, headers=ALICE)["state"] == "done"
        made["of_table"] = r.json()["hash"]
        # the table the tabulated render made in the table store (no record: read from its header)
        (made["render_table"],) = {p.stem for p in (folder / "tables").glob("*.exr")} - {made["table"]}
        yield c, data, ref, made


def absent(c, path: str, key: str):
    """The answer for a hash nothing has, at the same path."""
    return c.get(path.replace(key, ABSENT), headers=BOB)


def test_a_table_or_render_of_another_tenants_upload_is_as_absent(lab):
    """Before: bob, knowing the hash of alice's measured file, could not name it in a model
    (422), but could read what was made from it by its hash (computable from the request):
    the table's metadata and file, the render's record and images, and the table a render
    tabulated (200s). After: 404, worded as for a hash nothing has. Alice and an admin read them."""
    c, _, _, made = lab
    paths = [
        f"/v1/tables/{made['table']}",
        f"/v1/tables/{made['table']}/file",
        f"/v1/tables/{made['render_table']}",
        f"/v1/tables/{made['render_table']}/file",
    ]
    paths += [
        f"/v1/renders/{made[name]}{tail}"
        for name in ("render", "tabulated", "of_table")
        for tail in ("", "/image.png", "/image.exr")
    ]
    for path in paths:
        key = path.split("/")[3]
        r = c.get(path, headers=BOB)
        expected = absent(c, path, key)
        assert r.status_code == 404 and r.json()["detail"] == expected.json()["detail"].replace(ABSENT, key), (
            path,
            r.text,
        )
        for headers in (ALICE, OPS):
            assert c.get(path, headers=headers).status_code == 200, path


def test_another_tenants_table_of_an_upload_is_not_a_model(lab):
    """Before: bob named the table of alice's measured file by its hash in an evaluation, a
    lobe, a render's material, a layered model's base and a table: the upload's values came
    back (200 / 202), bypassing the check that keeps her file from him. After: the 422 of a
    table nothing has; alice still evaluates it."""
    c, _, _, made = lab
    for table in (made["table"], made["render_table"]):
        ref = {"type": "table", "hash": table}
        requests = [
            ("/v1/bsdf/eval", {"model": ref, **ANGLES}),
            ("/v1/bsdf/lobe", {"model": ref, "theta_i": 30.0, "points": 5, "resolution": 3}),
            ("/v1/renders", {**TINY, "options": {"material": ref}}),
            ("/v1/tables", {"model": {"type": "layered", "base": ref, "interfaces": []}, "grid": GRID}),
        ]
        for path, body in requests:
            r = c.post(path, json=body, headers=BOB)
            if r.status_code == 202:
                c.delete(f"/v1/jobs/{r.json()['id']}", headers=BOB)
            assert (
                r.status_code == 422
                and r.json()["detail"] == f"no table {table} in this server's store (GET /v1/tables)"
            ), (path, r.text)
        assert c.post("/v1/bsdf/eval", json={"model": ref, **ANGLES}, headers=ALICE).status_code == 200


def test_an_upload_of_the_same_bytes_makes_its_artefacts_the_uploaders(lab):
    """Holding the bytes is holding the data: once bob uploads the same file, the table and
    the render made from it are his to read, and his identical request gets them (200)."""
    c, data, ref, made = lab
    assert c.post("/v1/measured", params={"format": "rgl"}, content=data, headers={**BOB, **OCTETS}).status_code == 200
    assert c.get(f"/v1/tables/{made['table']}/file", headers=BOB).status_code == 200
    assert c.get(f"/v1/renders/{made['render']}/image.png", headers=BOB).status_code == 200
    again = c.post("/v1/tables", json={"model": ref, "grid": GRID}, headers=BOB)
    assert again.status_code == 200 and again.json()["hash"] == made["table"], again.text


@pytest.mark.parametrize("name", ["x.csv", "x.ProcSpec", "x.txt"])
def test_fit_data_does_not_tell_whether_another_tenant_uploaded_the_bytes(lab, tmp_path, name):
    """Before: bob, holding a file, uploaded it as fit data before and after alice uploaded it
    as a measured file: the reader's complaint, then "these bytes are stored as another kind
    of upload", so he learnt that some tenant holds that file. After: the reader's complaint
    both times (its check comes first). The lab's server, with bytes of this case's own (a
    description no other upload has): nobody uploaded them before. Mutation: the stored-kind
    check moved before the reading (service/uploads.py, before()) fails it."""
    c = lab[0]
    data = rgl_bytes(tmp_path, f"bob's file as {name}")

    def as_fit_data():
        r = c.post("/v1/fits/datasets", params={"name": name}, content=data, headers={**BOB, **OCTETS})
        assert r.status_code == 422, r.text
        return r.json()["detail"]

    before = as_fit_data()
    r = c.post("/v1/measured", params={"format": "rgl"}, content=data, headers={**ALICE, **OCTETS})
    assert r.status_code == 200, r.text
    assert as_fit_data() == before


@pytest.mark.parametrize(
    "keys, words",
    [
        ({"admin": {"key": "t" * 32}}, ["'admin'", "BSDFLAB_API_KEY"]),
        ({"alice": {"key": "a" * 32}, "bob": {"key": "a" * 32}}, ["'bob'", "same key as 'alice'"]),
    ],
)
def test_two_keys_never_share_a_tenant(tmp_path, keys, words):
    """Before: a tenant key named "admin" beside BSDFLAB_API_KEY was the admin's client by
    name (its uploads, its jobs: the uploads and jobs are recorded by name), and one key given
    to two names was silently the last one. After: the settings are refused, naming the key."""
    with pytest.raises(ValueError) as e:
        make_client(tmp_path, api_key="r" * 32, api_keys=keys)
    assert all(w in str(e.value) for w in words), str(e.value)
