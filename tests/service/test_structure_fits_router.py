"""/v1/fits with a [structure] config (issue 30): the structure + instrument fit, one dataset or
a [[dataset]] co-refinement whose entries name their uploads by hash, run as a job through the
real router. The fits are real and tiny (one slit, cone and azimuth node, few walkers and
steps); nothing of the fit is replaced. The sampler is seeded: the job's chain is the one
``bsdflab fit`` (load_structure_config + run_stack_study) draws for the same data and config, so
medians and MAP agree to rtol 1e-9 (summation order only)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import tomllib

from bsdflab.fit.full_stack_config import load_structure_config, parse_structure_config
from bsdflab.fit.stack_study import run_stack_study
from support.fit_figures import no_figures
from support.service_client import make_client, wait_job

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "fit"
STACK = (EXAMPLES / "stack_data.csv").read_bytes()
STRUCTURE = """
[structure]
exterior = "air"
substrate = { cauchy = [1.532, 5890.0] }

[[structure.layers]]
name = "film"
material = { n = 1.83 }
thickness_nm = 900.0

[parameters]
film_thickness_nm = { prior = "uniform", low = 860.0, high = 940.0 }

[model]
bandwidth_nodes = 1
cone_nodes = 1
cone_azimuths = 1

[sampler]
walkers = 8
max_steps = 60
check_every = 30
map_starts = 1
seed = 3
"""
ONE = (
    STRUCTURE
    + """
[instrument]
scale = { prior = "uniform", low = 0.5, high = 1.5 }
background = 0.01
"""
)


def _halves() -> tuple[bytes, bytes]:
    """stack_data.csv's rows split by angle: two datasets of one sample (15 and 45 degrees)."""
    lines = STACK.decode().splitlines(keepends=True)
    head = [x for x in lines if x.startswith("#") or x.startswith("angle_deg")]
    rows = [x for x in lines if x not in head]
    angles = sorted({x.split(",")[0] for x in rows})
    first = [x for x in rows if x.split(",")[0] == angles[0]]
    rest = [x for x in rows if x.split(",")[0] != angles[0]]
    assert first and rest
    return "".join(head + first).encode(), "".join(head + rest).encode()


A, B = _halves()


def two(a: str, b: str, key: str = "data") -> str:
    """A co-refinement: each dataset with its own scale (and the shared film)."""
    return (
        STRUCTURE
        + f"""
[[dataset]]
name = "a"
{key} = "{a}"
instrument = {{ scale = {{ prior = "uniform", low = 0.5, high = 1.5 }}, background = 0.01 }}

[[dataset]]
name = "b"
{key} = "{b}"
instrument = {{ scale = {{ prior = "uniform", low = 0.5, high = 1.5 }}, background = 0.01 }}
"""
    )


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("fits"), limit_body_bytes=256 << 10, limit_queue=4) as c:
        yield c


def upload(client, data: bytes, name: str, headers=None) -> str:
    r = client.post(
        "/v1/fits/datasets",
        params={"name": name},
        content=data,
        headers={"Content-Type": "application/octet-stream", **(headers or {})},
    )
    assert r.status_code == 200, r.text
    return r.json()["hash"]


def run_job(client, body) -> dict:
    r = client.post("/v1/fits", json=body)
    assert r.status_code == 202, r.text
    job = wait_job(client, r.json()["id"], timeout=600)
    assert job["state"] == "done", job
    info = client.get(job["links"]["artefact"]).json()
    assert info["state"] == "done" and {"summary.json", "parameters.csv", "corner.png", "draws.npz"} <= set(
        info["files"]
    ), info
    return {**client.get(info["links"]["summary.json"]).json(), "files": info["files"]}


def same(got: dict, want: dict) -> None:
    assert got["free"] == want["free"] and got["rows"] == want["rows"] and got["steps"] == want["steps"]
    for name in ("median", "map", "ci90_low", "ci90_high"):
        g = np.array([r[name] for r in got["parameters"]])
        w = np.array([r[name] for r in want["parameters"]])
        assert np.allclose(g, w, rtol=1e-9, atol=0), (name, g, w)


def test_a_structure_fit_as_a_job(client, tmp_path, monkeypatch):
    """One dataset: the job's study is the one ``bsdflab fit stack_data.csv --config`` writes
    (the reference without its figures: support/fit_figures.py). Mutation caught: the job's
    config with another sampler seed (bsdflab.fit.job.structure_config)."""
    h = upload(client, STACK, "stack_data.csv")
    summary = run_job(client, {"config": tomllib.loads(ONE), "data": [{"hash": h, "name": "stack_data.csv"}]})
    assert summary["model"] == "structure" and summary["free"] == ["film_thickness_nm", "scale"]
    (tmp_path / "config.toml").write_text(ONE)
    (tmp_path / "stack_data.csv").write_bytes(STACK)
    with no_figures(monkeypatch):
        want = run_stack_study(
            load_structure_config(tmp_path / "config.toml"),
            tmp_path / "study",
            str(tmp_path / "stack_data.csv"),
            progress=False,
        )
    same(summary, want)


def test_a_co_refinement_as_a_job(client, tmp_path, monkeypatch):
    """Two datasets, each its own scale, named by upload hash: the same study as the config
    naming the two files by path run locally (each dataset's rows, in order; the reference
    without its figures). Mutation caught: the job's config with another sampler seed."""
    ha, hb = upload(client, A, "at15.csv"), upload(client, B, "rest.csv")
    body = {
        "config": tomllib.loads(two(ha, hb, "hash")),
        "data": [{"hash": ha, "name": "at15.csv"}, {"hash": hb, "name": "rest.csv"}],
    }
    summary = run_job(client, body)
    assert summary["datasets"] == ["a", "b"] and summary["free"] == ["film_thickness_nm", "a.scale", "b.scale"]
    (tmp_path / "at15.csv").write_bytes(A)
    (tmp_path / "rest.csv").write_bytes(B)
    (tmp_path / "config.toml").write_text(two("at15.csv", "rest.csv"))
    with no_figures(monkeypatch):
        want = run_stack_study(load_structure_config(tmp_path / "config.toml"), tmp_path / "study", progress=False)
    same(summary, want)


@pytest.mark.parametrize(
    "data, words",
    [
        ("/etc/passwd", "config.dataset[0].data: a path is not accepted over HTTP"),
        ("at15.csv", "config.dataset[0].data: a path is not accepted over HTTP"),
    ],
)
def test_a_path_is_refused(client, data, words):
    ha = upload(client, A, "at15.csv")
    config = tomllib.loads(two(data, data))
    r = client.post("/v1/fits", json={"config": config, "data": [{"hash": ha, "name": "at15.csv"}]})
    assert r.status_code == 422 and words in r.json()["detail"], r.text


def test_bad_hash_references_are_422(client):
    ha, hb = upload(client, A, "at15.csv"), upload(client, B, "rest.csv")
    files = [{"hash": ha, "name": "at15.csv"}, {"hash": hb, "name": "rest.csv"}]
    r = client.post("/v1/fits", json={"config": tomllib.loads(two(ha, "cd" * 32, "hash")), "data": files})
    assert r.status_code == 422 and "config.dataset[1].hash" in r.text, r.text
    r = client.post("/v1/fits", json={"config": tomllib.loads(two(ha, ha, "hash")), "data": files})
    assert r.status_code == 422 and "data[1]: no [[dataset]] names hash" in r.text, r.text


@pytest.mark.parametrize(
    "edit, words",
    [
        ({"sampler": {"walkers": 8, "max_steps": 1 << 20}}, "BSDFLAB_LIMIT_FIT_WALKER_STEPS"),
        ({"sampler": {"kind": "nested", "live_points": 5000}}, "BSDFLAB_LIMIT_FIT_LIVE_POINTS"),
    ],
)
def test_an_over_limit_structure_fit_is_refused(client, edit, words):
    h = upload(client, STACK, "stack_data.csv")
    config = {**tomllib.loads(ONE), **edit}
    r = client.post("/v1/fits", json={"config": config, "data": [{"hash": h, "name": "stack_data.csv"}]})
    assert r.status_code == 422 and words in r.json()["detail"], r.text


def test_the_full_models_emulator_solves_are_limited(client):
    """The full-model structure's emulator: emulator_nodes ^ free structure parameters (here
    26^3 + checks past 2^14 is refused; 5^3 passes the limit check); no emulator: walkers x
    max_steps direct solves."""
    text = (EXAMPLES / "structure_full" / "structure.toml").read_text()
    data = (EXAMPLES / "structure_full" / "data.csv").read_bytes()
    h = upload(client, data, "full.csv")
    files = [{"hash": h, "name": "full.csv"}]
    config = tomllib.loads(text)
    for model, words in (
        ({"emulator_nodes": 26}, "emulator_nodes ^ free parameters + emulator_checks"),
        ({"emulator_nodes": 0}, "emulator_nodes = 0: walkers x max_steps + the MAP stage's direct solves"),
    ):
        r = client.post("/v1/fits", json={"config": {**config, "model": {**config["model"], **model}}, "data": files})
        assert r.status_code == 422 and "BSDFLAB_LIMIT_FIT_EMULATOR_SOLVES" in r.text and words in r.text, r.text


def test_another_tenants_hash_is_refused(tmp_path):
    """Bob naming alice's upload in a [[dataset]] gets the 422 of an absent upload."""
    from fastapi.testclient import TestClient

    from bsdflab.service import Settings, create_app

    alice, bob = {"X-API-Key": "a" * 32}, {"X-API-Key": "b" * 32}
    keys = {"alice": {"key": "a" * 32}, "bob": {"key": "b" * 32}}
    settings = Settings(data_dir=tmp_path, cache_dir=tmp_path / "tables", executor="threads", workers=1, api_keys=keys)
    with TestClient(create_app(settings)) as c:
        ha, hb = upload(c, A, "at15.csv", alice), upload(c, B, "rest.csv", bob)
        body = {
            "config": tomllib.loads(two(hb, ha, "hash")),
            "data": [{"hash": hb, "name": "rest.csv"}, {"hash": ha, "name": "at15.csv"}],
        }
        r = c.post("/v1/fits", json=body, headers=bob)
        assert r.status_code == 422 and f"data[1].hash: no uploaded fit data file {ha}" in r.text, r.text


def test_a_running_structure_fit_streams_progress_and_is_cancelled(client):
    """A co-refinement far too long to finish (2^21 walker steps, at the limit) reports its
    sampling stage (progress past 25 %) over the job's events, is cancelled within a sampler
    step, and serves no study. (The time guard only stops a hang; nothing is timed.)"""
    import json
    import time

    ha, hb = upload(client, A, "at15.csv"), upload(client, B, "rest.csv")
    config = tomllib.loads(two(ha, hb, "hash"))
    config["sampler"].update(max_steps=(1 << 18) - 1024, check_every=1 << 17)  # room for the MAP stage
    files = [{"hash": ha, "name": "at15.csv"}, {"hash": hb, "name": "rest.csv"}]
    r = client.post("/v1/fits", json={"config": config, "data": files})
    assert r.status_code == 202, r.text
    job_id = r.json()["id"]
    end = time.monotonic() + 1800   # a hang guard only (the MAP stage takes seconds), never a timing check
    while (job := client.get(f"/v1/jobs/{job_id}").json())["progress"] <= 0.25:
        assert job["state"] in ("queued", "running") and time.monotonic() < end, job
        time.sleep(0.05)
    with client.stream("GET", f"/v1/jobs/{job_id}/events") as events:
        lines = events.iter_lines()
        first = [next(lines), next(lines)]  # the job as it is now: a progress event
        assert first[0] == "event: progress" and json.loads(first[1].removeprefix("data:"))["progress"] > 0.25
        assert client.delete(f"/v1/jobs/{job_id}").status_code == 200
        rest = [line for line in lines if line.startswith("event:")]
    assert rest[-1] == "event: cancelled", rest
    job = wait_job(client, job_id, timeout=120)
    assert job["state"] == "cancelled" and "sampling cancelled" in job["error"], job
    assert client.get(f"/v1/fits/{job['hash']}/files/summary.json").status_code == 404


def test_a_full_model_structure_fit_as_a_job(client, tmp_path, monkeypatch):
    """The full model of a [structure] (its emulator: 3 nodes over one free structure
    parameter, 3 solves) over HTTP: the study ``bsdflab fit`` writes for the same config
    (the reference without its figures), and the emulator's solves counted as the limit
    counts them."""
    text = (EXAMPLES / "structure_full" / "structure.toml").read_text()
    data = (EXAMPLES / "structure_full" / "data.csv").read_bytes()
    config = tomllib.loads(text)
    config["model"].update(nodes=4, emulator_nodes=3, emulator_checks=1)
    config["parameters"] = {"base_albedo": config["parameters"]["base_albedo"]}
    config["sampler"] = {"walkers": 4, "max_steps": 20, "check_every": 10, "map_starts": 1, "seed": 3}
    h = upload(client, data, "full.csv")
    summary = run_job(client, {"config": config, "data": [{"hash": h, "name": "full.csv"}]})
    assert summary["emulator"]["solves"] == 3**1, summary["emulator"]
    assert "material.json" in summary["files"]  # the full model's posterior median, renderable
    (tmp_path / "data.csv").write_bytes(data)
    with no_figures(monkeypatch):
        want = run_stack_study(
            parse_structure_config(config), tmp_path / "study", str(tmp_path / "data.csv"), progress=False
        )
    same(summary, want)
