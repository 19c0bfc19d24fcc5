"""The second review of issue 33's new surface (fits as jobs), as a tenant would attack it.
Each test failed on the code before its fix (the before is in the test's docstring)."""

from __future__ import annotations

import ctypes
import io
import zipfile
from pathlib import Path

import numpy as np
import pytest

from support.service_client import make_client

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "fit"
LONG = (EXAMPLES / "data.csv").read_bytes()
PARAMETERS = {"film_thickness_nm": {"prior": "normal", "mean": 430.0, "sd": 10.0}}
SMALL = {"walkers": 8, "max_steps": 20}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(
        tmp_path_factory.mktemp("attack2"),
        limit_body_bytes=256 << 10,
        limit_measured_bytes=8 * len(LONG),
        limit_queue=4,
    ) as c:
        yield c


def upload(client, data: bytes, name: str):
    return client.post(
        "/v1/fits/datasets", params={"name": name}, content=data, headers={"Content-Type": "application/octet-stream"}
    )


def submit(client, body):
    """POST /v1/fits; a job the attack should never have queued is cancelled at once."""
    r = client.post("/v1/fits", json=body)
    if r.status_code == 202:
        client.delete(f"/v1/jobs/{r.json()['id']}")
    return r


def raw8_with_zip_bomb() -> bytes:
    """A valid AvaSoft 8 file (what the upload checks) with a zip appended (zip archives are
    read from their end): 65 MiB of one XML member deflated to about 64 KB."""
    from avaread.AvaTypes import AVSInfoBlock, AVSPreamble

    wl, dark, ref = np.array([400.0, 450.0, 500.0, 550.0, 600.0]), np.full(5, 100.0), np.full(5, 4100.0)
    info = AVSInfoBlock()
    info.Measurement.StartPixel, info.Measurement.StopPixel = 0, 4
    info.blockLength = ctypes.sizeof(info) + 16 * 5
    raw8 = (
        bytes(AVSPreamble(b"AVS", b"84", 1))
        + bytes(info)
        + np.concatenate([wl, dark + 2000, dark, ref]).astype(np.float32).tobytes()
    )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("ps_0.xml", b"<a>" + b" " * (65 << 20) + b"</a>")
    return raw8 + buf.getvalue()


@pytest.fixture(scope="module")
def polyglot(client):
    r = upload(client, raw8_with_zip_bomb(), "s_20deg.raw8")
    assert r.status_code == 200 and r.json()["format"] == "avantes-raw8", r.text
    return r.json()["hash"]


@pytest.mark.parametrize(
    "name, sidecar",
    [("s_20deg.ProcSpec", {"geometry": "specular"}), ("s_20deg.raw8", {"geometry": "specular", "format": "procspec"})],
)
def test_a_zip_bomb_uploaded_under_another_format_is_not_inflated(client, polyglot, name, sidecar):
    """Before: the upload was checked as the format its name gave (a raw8 file passes), but the
    fit reads it as the name or the sidecar's format in the fit request says: as a .ProcSpec, the
    appended zip inflated in the web process before the queue (a 300 KB upload: 300 MiB, 6 s,
    +600 MB RSS; 64 MiB of upload: tens of GB). After: the reader refuses it from its sizes."""
    r = submit(
        client,
        {
            "config": {"parameters": PARAMETERS, "sampler": SMALL},
            "data": [{"hash": polyglot, "name": name}],
            "sidecar": sidecar,
        },
    )
    assert r.status_code == 422 and "inflates to" in r.json()["detail"], r.text


@pytest.fixture(scope="module")
def long_hash(client):
    r = upload(client, LONG, "data.csv")
    assert r.status_code == 200, r.text
    return r.json()["hash"]


@pytest.mark.parametrize(
    "config, words",
    [
        (
            {"model": {"kind": "full", "emulator_nodes": 0}, "sampler": {"walkers": 32, "max_steps": 20000}},
            "emulator_nodes = 0: walkers x max_steps + the MAP stage's direct solves + emulator_checks",
        ),
        (
            {"model": {"kind": "full", "emulator_nodes": 0}, "sampler": {"kind": "nested"}},
            "emulator_nodes = 0 with the nested sampler",
        ),
        (
            {
                "sampler": SMALL,
                "appearance": {"draws": 100000, "renders": 0, "angles_deg": [float(a) for a in range(85)]},
            },
            "[appearance] draws x angles_deg",
        ),
    ],
)
def test_fit_work_limits_cannot_be_bypassed(client, long_hash, config, words):
    """Before: each was queued (202). The full model with emulator_nodes = 0 solves the model
    at every likelihood evaluation, so walkers x max_steps (2^21 passed the walker-step limit)
    were adding-doubling solves, and nested sampling had no bound at all; the appearance
    evaluated draws x angles (angles_deg of any length)."""
    r = submit(
        client, {"config": {"parameters": PARAMETERS, **config}, "data": [{"hash": long_hash, "name": "data.csv"}]}
    )
    assert r.status_code == 422 and words in r.json()["detail"], r.text


def test_one_upload_named_many_times_is_not_read_many_times(client, long_hash):
    """Before: the data list may name one upload under 64 names; each was copied and read in
    the web process before the queue (64 x a 64 MiB upload: 4 GiB). After: the data files
    together are bounded by BSDFLAB_LIMIT_MEASURED_BYTES, checked from their stored sizes."""
    data = [{"hash": long_hash, "name": f"part_{i}.csv"} for i in range(16)]
    r = submit(client, {"config": {"parameters": PARAMETERS, "sampler": SMALL}, "data": data})
    assert r.status_code == 422 and "BSDFLAB_LIMIT_MEASURED_BYTES" in r.json()["detail"], r.text


def test_the_service_checks_server_listens_on_loopback_only(tmp_path, monkeypatch):
    """The validation family "service" (a job any tenant may start: POST /v1/validations)
    starts a ``bsdflab serve`` of its own. Before: it took the parent's environment, and the
    container image sets BSDFLAB_HOST=0.0.0.0, so that server listened on every interface
    (the parent's table cache behind it). After: it is told 127.0.0.1."""
    import psutil

    from bsdflab.validation.checks.service import serve

    monkeypatch.setenv("BSDFLAB_HOST", "0.0.0.0")
    url, stop = serve(tmp_path)
    try:
        port = int(url.rsplit(":", 1)[1])
        listening = {
            c.laddr.ip for c in psutil.net_connections("tcp") if c.status == psutil.CONN_LISTEN and c.laddr.port == port
        }
    finally:
        stop()
    assert listening == {"127.0.0.1"}, listening


def test_a_clients_fit_data_is_read_once_at_a_time(client, long_hash):
    """Before: each POST /v1/fits read its data files in the web process before the queue,
    as many at once as the route's threads (40), each read up to BSDFLAB_LIMIT_MEASURED_BYTES.
    After: one read per client at once, sharing the lock of its uploads (429 while one runs);
    held here as an upload in progress holds it."""
    from bsdflab.service import uploads

    body = {
        "config": {"parameters": PARAMETERS, "sampler": {**SMALL, "seed": 7}},
        "data": [{"hash": long_hash, "name": "data.csv"}],
    }
    lock = uploads.client_lock("anonymous")
    with lock:
        r = submit(client, body)
    assert r.status_code == 429 and r.headers["Retry-After"], r.text
    assert submit(client, body).status_code == 202


def test_another_tenants_upload_is_not_fit_data(tmp_path):
    """Before: a fit could name any stored upload by its hash (the SHA-256 of the file, which
    a tenant can compute for a file it guesses): tenant b's fit of a's file was queued, and the
    study's data.csv handed a's rows back; the 202 / 422 told whether anyone had uploaded
    those bytes. After: only the client's own uploads (an admin's: any); another's is a 422
    worded as for no upload at all."""
    keys = {"a": {"key": "a" * 20}, "b": {"key": "b" * 20}, "ops": {"key": "o" * 20, "admin": True}}
    a, b, ops = ({"X-API-Key": k * 20} for k in "abo")
    with make_client(tmp_path, api_keys=keys, limit_body_bytes=256 << 10, limit_queue=8) as c:
        h = c.post("/v1/fits/datasets", params={"name": "d.csv"}, content=LONG, headers=a).json()["hash"]
        body = {"config": {"parameters": PARAMETERS, "sampler": SMALL}, "data": [{"hash": h, "name": "d.csv"}]}
        r = c.post("/v1/fits", json=body, headers=b)
        if r.status_code == 202:
            c.delete(f"/v1/jobs/{r.json()['id']}", headers=b)
        assert r.status_code == 422 and "no uploaded fit data file" in r.json()["detail"], r.text
        for headers in (a, ops):
            r = c.post("/v1/fits", json=body, headers=headers)
            assert r.status_code in (200, 202), r.text
            if r.status_code == 202:
                c.delete(f"/v1/jobs/{r.json()['id']}", headers=headers)


def test_another_tenants_measured_file_is_not_a_model(tmp_path):
    """Before: any client could name any stored measured file by its hash in an evaluation,
    a lobe, a table or a render (b evaluated a's upload: its values, and a 200 / 422 that told
    whether those bytes were stored). After: a client's own uploads only (an admin's: any);
    another's is the 422 of an absent file."""
    from bsdflab.measured.merl import DIMS, merl_bytes

    keys = {"a": {"key": "a" * 20}, "b": {"key": "b" * 20}, "ops": {"key": "o" * 20, "admin": True}}
    a, b, ops = ({"X-API-Key": k * 20} for k in "abo")
    merl = merl_bytes(0.01 + 0.5 * np.random.default_rng(5).random((3, *DIMS)))
    with make_client(tmp_path, api_keys=keys, limit_measured_bytes=64 << 20, limit_queue=8) as c:
        r = c.post(
            "/v1/measured",
            params={"format": "merl"},
            content=merl,
            headers={**a, "content-type": "application/octet-stream"},
        )
        assert r.status_code == 200, r.text
        ref = {"type": "merl", "hash": r.json()["hash"]}
        angles = {"theta_i": [30.0], "theta_o": [30.0], "phi": [180.0]}
        requests = [
            ("/v1/bsdf/eval", {"model": ref, **angles}),
            ("/v1/bsdf/lobe", {"model": ref, "theta_i": 30.0, "points": 9, "resolution": 5}),
            ("/v1/tables", {"model": ref, "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}}),
            ("/v1/renders", {"scene": "sphere", "options": {"material": ref}, "width": 4, "height": 4, "spp": 1}),
        ]
        for path, body in requests:
            r = c.post(path, json=body, headers=b)
            if r.status_code == 202:
                c.delete(f"/v1/jobs/{r.json()['id']}", headers=b)
            assert r.status_code == 422 and "in this server's store" in r.text, (path, r.text)
        for headers in (a, ops):
            r = c.post("/v1/bsdf/eval", json={"model": ref, **angles}, headers=headers)
            assert r.status_code == 200, r.text


def test_a_sidecars_regular_expression_is_not_run(client):
    """Before: the sidecar's name_pattern, a client's regular expression, was matched against
    the client's file and column names in the web process at submission (and in the worker);
    Python's re holds the GIL while it backtracks, so ``^(?P<angle>(a+)+)$`` against a name of
    22 a's and a dash took 0.33 s, about 3.3 times more per 2 characters (names may have 128:
    the server, /healthz included, stops for ever). After: refused over HTTP (422)."""
    wide = (EXAMPLES / "wide" / "angles.csv").read_bytes()
    name = "a" * 100 + "-.csv"
    h = upload(client, wide, name).json()["hash"]
    sidecar = {"geometry": "specular", "units": "percent", "name_pattern": "^(?P<angle>(a+)+)$"}
    r = submit(
        client,
        {
            "config": {"parameters": PARAMETERS, "sampler": SMALL},
            "data": [{"hash": h, "name": name}],
            "sidecar": sidecar,
        },
    )
    assert r.status_code == 422 and "name_pattern is not accepted over HTTP" in r.json()["detail"], r.text


def test_a_procspec_of_much_xml_is_refused_before_parsing(tmp_path):
    """Before: a 160 KB .ProcSpec whose document inflates to 63 MiB of ``<double>`` elements
    (under the 64 MiB bound) was parsed at upload in the web process: 8.8 s with the GIL held
    and +412 MB. After: 4 MiB at most (a real document is under 1 MB)."""
    n = (63 << 20) // 36
    xml = (
        b"<a><channelWavelengths>"
        + b"<double>1</double>" * n
        + b"</channelWavelengths><processedPixels>"
        + b"<double>1</double>" * n
        + b"</processedPixels></a>"
    )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("ps_0.xml", xml)
    assert len(buf.getvalue()) < 256 << 10
    with make_client(tmp_path, limit_measured_bytes=1 << 20) as c:
        r = upload(c, buf.getvalue(), "s_20deg.ProcSpec")
    assert r.status_code == 422 and "inflates to" in r.json()["detail"], r.text
