"""/v1/fits (issue 33, "fits as jobs"): data files uploaded by hash in the formats the fit
reads, a fitting study run as a job (bsdflab.fit.job), its folder's files served by name,
cancellable, under the job limits. The fits are real (tiny configs: few walkers and steps,
the smooth model with one thickness node); nothing of the fit is replaced."""
from __future__ import annotations

import io
import json
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from bsdflab import from_dict
from bsdflab.fit import FitConfig, run_study
from bsdflab.fit.readers import ImportSpec, import_files, parse_spec
from support.fit_figures import no_figures
from support.service_client import make_client, wait_job

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "fit"
LONG = (EXAMPLES / "data.csv").read_bytes()
WIDE = (EXAMPLES / "wide" / "angles.csv").read_bytes()
CONFIG = {"parameters": {"film_thickness_nm": {"prior": "normal", "mean": 430.0, "sd": 10.0},
                         "film_ior": {"prior": "normal", "mean": 1.83, "sd": 0.02}},
          "model": {"thickness_nodes": 1},
          "sampler": {"walkers": 8, "max_steps": 120, "check_every": 40, "map_starts": 1, "seed": 3},
          "appearance": {"draws": 4, "renders": 0, "angles_deg": [0, 30]}}
STUDY_FILES = {"summary.json", "material.json", "posterior.nc", "corner.png", "trace.png", "predictive.png",
               "residuals.png", "appearance.png", "parameters.csv", "data.csv"}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("fits"), limit_body_bytes=256 << 10, limit_queue=4) as c:
        yield c


def upload(client, data: bytes, name: str):
    return client.post("/v1/fits/datasets", params={"name": name}, content=data,
                       headers={"Content-Type": "application/octet-stream"})


@pytest.fixture(scope="module")
def long_hash(client):
    r = upload(client, LONG, "data.csv")
    assert r.status_code == 200, r.text
    assert r.json()["format"] == "long" and r.json()["summary"]["rows"] == 189
    return r.json()["hash"]


def test_a_fit_as_a_job(client, long_hash, tmp_path, monkeypatch):
    """The job's study is the one ``run_study`` writes for the same data and config (the
    sampler is seeded: the same draws, so the same posterior mean and MAP to the last bits
    up to summation order; the reference without its figures: support/fit_figures.py); the
    same request again answers 200 from the store. Mutation caught: the job's config with
    another sampler seed (bsdflab.fit.job.config_of)."""
    body = {"config": CONFIG, "data": [{"hash": long_hash, "name": "data.csv"}]}
    r = client.post("/v1/fits", json=body)
    assert r.status_code == 202, r.text
    job = wait_job(client, r.json()["id"], timeout=600)
    assert job["state"] == "done", job
    info = client.get(job["links"]["artefact"]).json()
    assert info["state"] == "done" and STUDY_FILES <= set(info["files"]), info
    summary = client.get(info["links"]["summary.json"]).json()
    assert summary["free"] == ["film_thickness_nm", "film_ior"] and summary["rows"] == 189
    material = client.get(f"/v1/fits/{info['hash']}/files/material.json")
    assert material.headers["content-type"].startswith("application/json")
    from_dict(material.json())   # a model bsdflab reads
    png = client.get(f"/v1/fits/{info['hash']}/files/corner.png")
    assert png.status_code == 200 and png.content[:8] == b"\x89PNG\r\n\x1a\n"

    (tmp_path / "data.csv").write_bytes(LONG)
    dataset, _ = import_files([str(tmp_path / "data.csv")], ImportSpec(source="sidecar"))
    with no_figures(monkeypatch):
        reference = run_study(dataset, FitConfig.parse(CONFIG), tmp_path / "study", progress=False)
    for name in ("posterior_mean", "map"):
        got, want = summary[name], reference[name]
        assert got.keys() == want.keys()
        bad = {k: (got[k], want[k]) for k in got if not np.isclose(got[k], want[k], rtol=1e-9, atol=0, equal_nan=True)}
        assert not bad, (name, bad)

    again = client.post("/v1/fits", json=body)
    assert again.status_code == 200 and again.json()["hash"] == info["hash"]


def test_a_wide_csv_with_its_sidecar(client, tmp_path):
    """The wide CSV is read with the request's sidecar at submission: a sidecar that places
    no curve is a 422 naming the file's column; with the example's sidecar the fit runs."""
    r = upload(client, WIDE, "angles.csv")
    assert r.status_code == 200 and r.json()["format"] == "wide", r.text
    files = [{"hash": r.json()["hash"], "name": "angles.csv"}]
    sidecar = {"geometry": "specular", "units": "percent"}
    wrong = client.post("/v1/fits", json={"config": CONFIG, "data": files,
                                          "sidecar": {**sidecar, "columns": {"R_99deg": {"angle_deg": 10}}}})
    assert wrong.status_code == 422 and "R_99deg" in wrong.text, wrong.text
    ok = client.post("/v1/fits", json={"config": {**CONFIG, "sampler": {**CONFIG["sampler"], "max_steps": 40}},
                                       "data": files, "sidecar": sidecar})
    assert ok.status_code == 202, ok.text
    job = wait_job(client, ok.json()["id"], timeout=600)
    assert job["state"] == "done", job
    summary = client.get(f"/v1/fits/{job['hash']}/files/summary.json").json()
    (tmp_path / "angles.csv").write_bytes(WIDE)
    dataset, _ = import_files([str(tmp_path / "angles.csv")], parse_spec(sidecar, "sidecar"))
    assert summary["rows"] == len(dataset) > 0


def _with(path: list[str], value):
    config = json.loads(json.dumps(CONFIG))
    node = config
    for key in path[:-1]:
        node = node.setdefault(key, {})
    node[path[-1]] = value
    return config


@pytest.mark.parametrize("config, words", [
    (_with(["sampler", "walkers"], 9), "[sampler] walkers must be even"),
    (_with(["sampler", "walkers"], 2), "[sampler] walkers"),
    (_with(["parameters", "no_such_parameter"], 1.0), "no_such_parameter"),
    (_with(["model", "kind"], "glossy"), "[model] kind"),
    (_with(["appearance", "angles_deg"], [95]), "[appearance] angles_deg"),
    (_with(["priors"], {}), "unknown key(s) priors"),
    (_with(["sampler", "max_steps"], 1_000_000), "BSDFLAB_LIMIT_FIT_WALKER_STEPS"),
    ({**CONFIG, "appearance": {"renders": 64, "render_size": 1024, "render_spp": 65536}},
     "BSDFLAB_LIMIT_RENDER_SAMPLES"),
])
def test_bad_configs_are_422_naming_the_field(client, long_hash, config, words):
    r = client.post("/v1/fits", json={"config": config, "data": [{"hash": long_hash, "name": "data.csv"}]})
    assert r.status_code == 422 and words in r.json()["detail"], r.text


@pytest.mark.parametrize("data, words", [
    ([{"hash": "ab" * 32, "name": "data.csv"}], "data[0].hash: no uploaded fit data file"),
    ([{"hash": "AB" * 32, "name": "data.csv"}], "hash"),
    ([{"hash": None, "name": "../../etc/passwd.csv"}], "data"),
    ([], "data"),
])
def test_bad_data_references_are_422(client, data, words):
    r = client.post("/v1/fits", json={"config": CONFIG, "data": data})
    assert r.status_code == 422 and words in r.text, r.text


def test_file_names_and_sidecars_name_no_server_path(client, long_hash):
    for name in ("../data.csv", "/etc/passwd", ".hidden.csv", "a/b.csv"):
        r = client.post("/v1/fits", json={"config": CONFIG, "data": [{"hash": long_hash, "name": name}]})
        assert r.status_code == 422 and "plain file name" in r.text, r.text
    r = client.post("/v1/fits", json={"config": CONFIG, "data": [{"hash": long_hash, "name": "data.csv"}],
                                      "sidecar": {"reference": {"file": "/etc/hostname"}}})
    assert r.status_code == 422 and "not accepted over HTTP" in r.text, r.text


def _procspec(members: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in members.items():
            z.writestr(name, data)
    return buf.getvalue()


def test_bad_uploads_are_422_naming_file_line_and_column(client):
    """A reader's complaint names the client's file name and the place, never the store."""
    bad = LONG.replace(b"0.06277386374", b"0.06x77", 1)
    r = upload(client, bad, "scan.csv")
    text = r.json()["detail"]
    assert r.status_code == 422 and "scan.csv" in text and "line 5" in text and "reflectance" in text, text
    assert ".upload-" not in text and str(Path.cwd()) not in text and "/tmp" not in text, text
    xml = b"<a><channelWavelengths><double>400</double></channelWavelengths><processedPixels>" \
          b"<double>1</double></processed></a>"
    r = upload(client, _procspec({"ps_0.xml": xml}), "s_20deg.ProcSpec")
    assert r.status_code == 422 and "s_20deg.ProcSpec: ps_0.xml: line 1, column" in r.json()["detail"], r.text
    for name in ("../x.csv", "x/y.csv", ".x.csv"):
        assert upload(client, LONG, name).status_code == 422


def test_a_procspec_zip_bomb_is_refused_before_inflating(client):
    """65 MiB of zeros deflate to ~64 KB: refused from the archive's declared sizes."""
    bomb = _procspec({"ps_0.xml": b"<a>" + b" " * (65 << 20) + b"</a>"})
    assert len(bomb) < 256 << 10
    r = upload(client, bomb, "bomb.ProcSpec")
    assert r.status_code == 422 and "inflates to" in r.json()["detail"], r.text


def test_a_running_fit_is_cancelled(client, long_hash):
    """A fit far too long to finish (2^21 walker steps) is cancelled once it samples (its
    progress past the MAP stage): the sampler loop sees the cancel, the job ends cancelled
    and no study is served."""
    config = _with(["sampler", "max_steps"], (1 << 18) - 1024)  # room for the MAP stage
    config["sampler"]["check_every"] = 1 << 17
    r = client.post("/v1/fits", json={"config": config, "data": [{"hash": long_hash, "name": "data.csv"}]})
    assert r.status_code == 202, r.text
    job_id = r.json()["id"]
    end = time.monotonic() + 1800   # a hang guard only (the MAP stage takes seconds), never a timing check
    while (job := client.get(f"/v1/jobs/{job_id}").json())["progress"] <= 0.25:
        assert job["state"] in ("queued", "running") and time.monotonic() < end, job
        time.sleep(0.05)
    assert client.delete(f"/v1/jobs/{job_id}").status_code == 200
    job = wait_job(client, job_id, timeout=120)
    assert job["state"] == "cancelled" and "sampling cancelled" in job["error"], job
    assert client.get(f"/v1/fits/{job['hash']}/files/summary.json").status_code == 404


def test_artefact_names_cannot_leave_the_study(client, long_hash):
    """Only the names the study wrote are served: a traversal, a file of the store beside the
    study (the upload itself) and a name it did not write are 404/422, never a file."""
    body = {"config": CONFIG, "data": [{"hash": long_hash, "name": "data.csv"}]}
    h = client.post("/v1/fits", json=body).json()["hash"]   # done in test_a_fit_as_a_job (200), or joins it
    wait = client.get(f"/v1/fits/{h}").json()
    if wait["state"] != "done":
        wait_job(client, wait["job"]["id"], timeout=600)
    assert client.get(f"/v1/fits/{h}/files/summary.json").status_code == 200
    # (a bare ".." never arrives: the client resolves the dot segment before sending)
    for name in ("..%2Fsettings.json", "%2e%2e", "%2e%2e%2f%2e%2e%2fjobs.sqlite", f"{long_hash}.fitdata",
                 "summary.json.tmp", "config.toml", "%2Fetc%2Fpasswd"):
        r = client.get(f"/v1/fits/{h}/files/{name}")
        assert r.status_code in (404, 422), (name, r.status_code, r.text)
        assert LONG not in r.content and b"SQLite" not in r.content


def test_fit_data_counts_against_the_upload_quota(tmp_path):
    """Fit data share the measured uploads' storage quota (one count per key): the long CSV
    fits, the wide CSV then passes the quota (413 naming it), the same bytes again cost
    nothing, and the upload gate covers the path. Mutation caught: no quota check in
    fit_uploads (the wide CSV answers 200)."""
    from bsdflab.service.upload_gate import UPLOAD_PATHS

    assert "/v1/fits/datasets" in UPLOAD_PATHS
    with make_client(tmp_path, limit_upload_storage_per_key=len(LONG) + len(WIDE) // 2) as c:
        assert upload(c, LONG, "data.csv").status_code == 200
        assert upload(c, LONG, "again.csv").status_code == 200   # already stored: free
        r = upload(c, WIDE, "angles.csv")
        assert r.status_code == 413 and "BSDFLAB_LIMIT_UPLOAD_STORAGE_PER_KEY" in r.text, r.text
        assert c.get("/v1/fits/datasets").json()["datasets"][0]["summary"]["bytes"] == len(LONG)


def test_a_fit_never_shows_another_tenants_job(tmp_path):
    """Bob, who knows the hash of alice's running fit, gets 404 naming no job, cannot cancel
    it, and does not see her uploads listed; alice sees and cancels it."""
    from fastapi.testclient import TestClient

    from bsdflab.service import Settings, create_app

    alice, bob = {"X-API-Key": "a" * 32}, {"X-API-Key": "b" * 32}
    keys = {"alice": {"key": "a" * 32}, "bob": {"key": "b" * 32}}
    settings = Settings(data_dir=tmp_path, cache_dir=tmp_path / "tables",
                        executor="threads", workers=1, api_keys=keys, progress_interval_s=0.05)
    with TestClient(create_app(settings)) as c:
        up = c.post("/v1/fits/datasets", params={"name": "data.csv"}, content=LONG,
                    headers={**alice, "Content-Type": "application/octet-stream"}).json()
        config = _with(["sampler", "max_steps"], (1 << 18) - 1024)  # room for the MAP stage
        job = c.post("/v1/fits", json={"config": config, "data": [{"hash": up["hash"], "name": "data.csv"}]},
                     headers=alice).json()
        try:
            seen = c.get(f"/v1/fits/{job['hash']}", headers=bob)
            assert seen.status_code == 404 and job["id"] not in seen.text, seen.text
            assert c.delete(f"/v1/jobs/{job['id']}", headers=bob).status_code == 404
            assert c.get("/v1/fits/datasets", headers=bob).json()["datasets"] == []
            assert job["id"] in c.get(f"/v1/fits/{job['hash']}", headers=alice).text
        finally:
            assert c.delete(f"/v1/jobs/{job['id']}", headers=alice).status_code == 200
        assert wait_job(c, job["id"], timeout=300, headers=alice)["state"] == "cancelled"


def test_a_finished_fit_is_only_shown_to_a_client_holding_its_data(tmp_path):
    """Bob, sending alice's exact request (he knows her data's hash), got her finished study
    from the cache, data.csv included, and read it by hash: now the request is a 422 naming
    the upload, the study and its files 404s. Once bob uploads the same file himself he holds
    the data, and the cached study is his too (200, not a second run). Mutation caught:
    _prepare without its ``_may_read`` (bob's request answers 200 from the cache)."""
    from fastapi.testclient import TestClient

    from bsdflab.service import Settings, create_app

    alice, bob = {"X-API-Key": "a" * 32}, {"X-API-Key": "b" * 32}
    keys = {"alice": {"key": "a" * 32}, "bob": {"key": "b" * 32}}
    settings = Settings(data_dir=tmp_path, cache_dir=tmp_path / "tables",
                        executor="threads", workers=1, api_keys=keys, progress_interval_s=0.05)
    octet = {"Content-Type": "application/octet-stream"}
    with TestClient(create_app(settings)) as c:
        up = c.post("/v1/fits/datasets", params={"name": "data.csv"}, content=LONG, headers={**alice, **octet}).json()
        # a short run (40 steps): who may see a finished study does not depend on its length
        body = {"config": {**CONFIG, "sampler": {**CONFIG["sampler"], "max_steps": 40},
                           "appearance": {"draws": 2, "renders": 0, "angles_deg": [0]}},
                "data": [{"hash": up["hash"], "name": "data.csv"}]}
        job = c.post("/v1/fits", json=body, headers=alice).json()
        assert wait_job(c, job["id"], timeout=600, headers=alice)["state"] == "done"
        study = job["hash"]
        assert c.get(f"/v1/fits/{study}/files/data.csv", headers=alice).status_code == 200

        again = c.post("/v1/fits", json=body, headers=bob)
        assert again.status_code == 422 and "data[0].hash" in again.text, again.text
        assert c.get(f"/v1/fits/{study}", headers=bob).status_code == 404
        for name in ("data.csv", "summary.json", "material.json"):
            r = c.get(f"/v1/fits/{study}/files/{name}", headers=bob)
            assert r.status_code == 404 and "data_row" not in r.text, (name, r.text)

        assert c.post("/v1/fits/datasets", params={"name": "mine.csv"}, content=LONG,
                      headers={**bob, **octet}).status_code == 200
        mine = c.post("/v1/fits", json=body, headers=bob)
        assert mine.status_code == 200 and mine.json()["hash"] == study, mine.text
        assert c.get(f"/v1/fits/{study}/files/data.csv", headers=bob).status_code == 200
