"""The same bytes uploaded as another kind (a measured file's bytes as fit data, fit data's
bytes as a measured file) by another tenant: the answer is the reader's, as for bytes
nobody stored, so it does not tell that someone uploaded them."""

from __future__ import annotations

from pathlib import Path

import pytest

from bsdflab.bsdfs import RoughConductor
from bsdflab.measured import export_model
from support.service_client import make_client

LONG = (Path(__file__).resolve().parents[2] / "examples" / "fit" / "data.csv").read_bytes()
OCTETS = {"content-type": "application/octet-stream"}
KEYS = {"a": {"key": "a" * 20}, "b": {"key": "b" * 20}}
A, B = ({"X-API-Key": k * 20, **OCTETS} for k in "ab")


@pytest.fixture(scope="module")
def rgl(tmp_path_factory) -> bytes:
    path = tmp_path_factory.mktemp("kinds") / "cu.bsdf"
    export_model(RoughConductor(alpha=0.2, material="Cu"), path, n_theta_i=4, resolution=8, error_points=100)
    return path.read_bytes()


def test_another_tenants_bytes_of_another_kind_get_the_readers_answer(tmp_path, rgl):
    """Before: once tenant a had stored bytes as one kind, tenant b's upload of them as the
    other kind answered "these bytes are stored as another kind of upload" before any
    reading (the measured route named its temporary, "upload.bsdf"): whether anyone had
    uploaded a given file, told to any key. Now the bytes are read first and b gets the
    reader's complaint, word for word the one it got before a's upload. Mutation caught:
    the kind compared before the check (both answers differ)."""
    with make_client(tmp_path, api_keys=KEYS, limit_measured_bytes=1 << 20, limit_body_bytes=256 << 10) as c:

        def as_measured(headers):
            return c.post("/v1/measured", params={"format": "rgl"}, content=LONG, headers=headers)

        def as_fit_data(headers):
            return c.post("/v1/fits/datasets", params={"name": "scan.csv"}, content=rgl, headers=headers)

        before = [as_measured(B), as_fit_data(B)]
        assert [r.status_code for r in before] == [422, 422], [r.text for r in before]
        assert as_measured(A).status_code == 422  # fit data does not read as a measured file
        assert c.post("/v1/fits/datasets", params={"name": "d.csv"}, content=LONG, headers=A).status_code == 200
        assert c.post("/v1/measured", params={"format": "rgl"}, content=rgl, headers=A).status_code == 200
        after = [as_measured(B), as_fit_data(B)]
    assert [r.status_code for r in after] == [422, 422], [r.text for r in after]
    assert [r.json()["detail"] for r in after] == [r.json()["detail"] for r in before]


def test_another_tenants_fit_data_under_a_name_it_does_not_read_as_gets_the_readers_answer(tmp_path):
    """A fit data file's name tells its reader (its suffix). Before: stored bytes were
    reused whatever the name, so tenant b's upload of a's CSV as "scan.ProcSpec" answered
    200 (a's record) once a had uploaded it and 422 ("not a readable zip") before: whether
    anyone had uploaded a file, told to any key. Now a stored file answers only a name of
    its first upload's suffix (the same reader); another name is read. Mutation caught:
    reuse whatever the name (200 after)."""
    with make_client(tmp_path, api_keys=KEYS, limit_measured_bytes=1 << 20, limit_body_bytes=256 << 10) as c:

        def upload(name, headers):
            return c.post("/v1/fits/datasets", params={"name": name}, content=LONG, headers=headers)

        before = upload("scan.ProcSpec", B)
        assert before.status_code == 422, before.text
        stored = upload("d.csv", A)
        assert stored.status_code == 200, stored.text
        after = upload("scan.ProcSpec", B)
        same_reader = upload("e.CSV", B)
    assert after.status_code == 422 and after.json()["detail"] == before.json()["detail"], after.text
    assert same_reader.status_code == 200 and same_reader.json() == stored.json()
