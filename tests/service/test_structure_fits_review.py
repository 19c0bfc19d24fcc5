"""/v1/fits with [structure] configs, as an attacker would send them (an adversarial review):
work the limit check must count (the instrument quadrature, the MAP stage, one solve's cost),
the [appearance] table refused, an upload named config.toml refused, too few walkers a 422,
and 4xx (never 5xx or a failed job) for malformed structure keys. Each test failed before
its fix."""

from __future__ import annotations

import copy
import sys
from pathlib import Path

import pytest
import tomllib

from support.service_client import make_client, wait_job

TESTS = Path(__file__).resolve().parent
sys.path.insert(0, str(TESTS))
from test_structure_fits_router import EXAMPLES, ONE, STACK, A, B, two, upload  # noqa: E402

FULL = tomllib.loads((EXAMPLES / "structure_full" / "structure.toml").read_text())
FULL_DATA = (EXAMPLES / "structure_full" / "data.csv").read_bytes()


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with make_client(tmp_path_factory.mktemp("fitsrev"), limit_body_bytes=256 << 10, limit_queue=8) as c:
        yield c


def post(client, body):
    """The limit check the route runs (bsdflab.service.routers.fits.check_limits) on the
    normalised request, with the service's default limits: 422 or 202 (nothing is queued)."""
    from fastapi import HTTPException

    from bsdflab.fit import job as fit_job
    from bsdflab.service import Settings
    from bsdflab.service.routers.fits import check_limits

    class R:
        def __init__(self, code, text):
            self.status_code, self.text = code, text

    try:
        request = fit_job.normalise(body)
        check_limits(Settings(), request)
    except (ValueError, HTTPException) as e:
        return R(422, str(getattr(e, "detail", e)))
    return R(202, "accepted by check_limits (default limits)")


def one_body(client, config):
    h = upload(client, STACK, "stack_data.csv")
    return {"config": config, "data": [{"hash": h, "name": "stack_data.csv"}]}


def full_body(client, config):
    h = upload(client, FULL_DATA, "full.csv")
    return {"config": config, "data": [{"hash": h, "name": "full.csv"}]}


def test_smooth_stack_quadrature_is_counted(client):
    """walkers x max_steps at the limit (2^21) with the instrument's quadrature at its maximum
    (63 slit x 64 cone x 64 azimuth nodes; a slit and a cone given) is accepted: the per-step
    cost is not in check_limits. Measured (2 loaded cores, stack_data.csv's 124 rows): one
    8-walker step 24 s against 0.018 s at the defaults (1350x); 2^21 walker steps ~1700 CPU h,
    and MAP's 256-point prior pool is one uncancellable batch of ~13 min."""
    config = tomllib.loads(ONE)
    config["model"] = {"bandwidth_nodes": 63, "cone_nodes": 64, "cone_azimuths": 64}
    config["instrument"].update(acceptance_deg=2.0, bandwidth_nm=0.3)
    config["sampler"].update(walkers=8, max_steps=1 << 18)
    r = post(client, one_body(client, config))
    assert r.status_code == 422, r.text


def test_full_model_solver_cost_is_counted(client):
    """The full model at nodes = 256, orders = 4096 (each adding-doubling solve at its maximum
    cost) and emulator_nodes = 0 (walkers x max_steps direct solves, here 2^14 = the limit) is
    accepted: the solves are counted, not what one costs."""
    config = copy.deepcopy(FULL)
    config["model"].update(nodes=256, orders=4096, emulator_nodes=0, emulator_checks=0)
    config["sampler"].update(walkers=16, max_steps=1 << 10, map_starts=1)
    r = post(client, full_body(client, config))
    assert r.status_code == 422, r.text


def test_map_starts_direct_solves_are_counted(client):
    """emulator_nodes = 0: the limit counts walkers x max_steps direct solves, but the MAP stage
    runs map_starts (up to 1000) L-BFGS-B optimisations of up to 500 iterations, each a finite-
    difference gradient (free + 1 direct solves): ~2e6 uncounted solves, past the 2^14 limit."""
    config = copy.deepcopy(FULL)
    config["model"].update(emulator_nodes=0, emulator_checks=0)
    config["sampler"].update(walkers=16, max_steps=10, map_starts=1000)
    r = post(client, full_body(client, config))
    assert r.status_code == 422, r.text


def test_appearance_in_a_structure_config_is_refused(client):
    """A structure study makes no appearance draws or renders; an [appearance] table is parsed,
    skipped by check_limits and silently ignored (and makes a distinct job key for the same
    study). It should be a 422 naming [appearance]."""
    config = tomllib.loads(ONE)
    config["appearance"] = {"renders": 64, "render_size": 1024, "render_spp": 65536, "draws": 100000}
    r = post(client, one_body(client, config))
    assert r.status_code == 422 and "appearance" in r.text, r.text


BAD = [None, True, "x", "1e9", [], {}, [1, 2], {"a": {"b": 1}}, 10**400, -(10**400), 1e308, -1.0, 0]
KEYS = [
    ("structure",),
    ("structure", "exterior"),
    ("structure", "substrate"),
    ("structure", "layers"),
    ("structure", "layers", 0),
    ("structure", "layers", 0, "material"),
    ("structure", "layers", 0, "thickness_nm"),
    ("structure", "layers", 0, "name"),
    ("parameters",),
    ("parameters", "film_thickness_nm"),
    ("parameters", "film_thickness_nm", "low"),
    ("parameters", "film_thickness_nm", "prior"),
    ("model",),
    ("model", "bandwidth_nodes"),
    ("model", "kind"),
    ("sampler",),
    ("sampler", "walkers"),
    ("sampler", "kind"),
    ("instrument",),
    ("instrument", "scale"),
    ("instrument", "background"),
    ("appearance",),
    ("dataset",),
]


def _set(d, path, v):
    for k in path[:-1]:
        d = d[k]
    d[path[-1]] = v


@pytest.mark.parametrize("path", KEYS, ids=lambda p: ".".join(map(str, p)))
def test_malformed_structure_keys_are_4xx(client, path):
    """Every malformed value of a structure key is a 4xx (JSON cannot carry NaN; huge ints,
    wrong types and nested objects can)."""
    h = upload(client, STACK, "stack_data.csv")
    bad = []
    for v in BAD:
        config = tomllib.loads(ONE)
        config["sampler"].update(max_steps=10, walkers=4)
        _set(config, path, v)
        try:
            r = client.post("/v1/fits", json={"config": config, "data": [{"hash": h, "name": "stack_data.csv"}]})
        except Exception as e:  # a server exception (500)
            bad.append((v, repr(e)[:200]))
            continue
        if r.status_code >= 500:
            bad.append((v, r.status_code, r.text[:200]))
        elif r.status_code == 202:  # a valid value (0, a number): the job is not the point here
            client.delete(f"/v1/jobs/{r.json()['id']}")
    assert not bad, bad


def test_malformed_dataset_entries_are_4xx(client):
    ha, hb = upload(client, A, "at15.csv"), upload(client, B, "rest.csv")
    files = [{"hash": ha, "name": "at15.csv"}, {"hash": hb, "name": "rest.csv"}]
    base = tomllib.loads(two(ha, hb, "hash"))
    bad = []
    for edit in (
        {"hash": [ha]},
        {"hash": {"x": 1}},
        {"name": 5},
        {"name": "../x"},
        {"instrument": "x"},
        {"instrument": {"scale": {"prior": 1}}},
        {"extra": 1},
        {"hash": ha.upper()},
    ):
        config = copy.deepcopy(base)
        config["dataset"][0].update(edit)
        try:
            r = client.post("/v1/fits", json={"config": config, "data": files})
        except Exception as e:
            bad.append((edit, repr(e)[:200]))
            continue
        if r.status_code >= 500 or r.status_code == 202:
            bad.append((edit, r.status_code, r.text[:200]))
    assert not bad, bad


def test_an_upload_named_config_toml_is_not_the_studys_config(client):
    """The job copies each upload under its given name into the folder whose config.toml
    run_stack_study copies into the study: an upload named "config.toml" is served as the
    study's config.toml (a data CSV as the config). The name should be refused, or the
    study's config.toml be the request's config."""
    ha, hb = upload(client, A, "at15.csv"), upload(client, B, "rest.csv")
    config = tomllib.loads(two(ha, hb, "hash"))
    config["sampler"].update(walkers=8, max_steps=10, map_starts=1)
    r = client.post(
        "/v1/fits",
        json={"config": config, "data": [{"hash": ha, "name": "config.toml"}, {"hash": hb, "name": "rest.csv"}]},
    )
    if r.status_code == 422:
        return
    assert r.status_code == 202, r.text
    job = wait_job(client, r.json()["id"], timeout=600)
    assert job["state"] == "done", job
    info = client.get(job["links"]["artefact"]).json()
    if "config.toml" in info["files"]:
        text = client.get(info["links"]["config.toml"]).text
        assert not text.startswith("# SYNTHETIC DATA"), text[:200]


def test_too_few_walkers_for_the_free_parameters_is_422(client):
    """walkers < 2 x free parameters (film, a.scale, b.scale: 6) passes the submit-time check
    and the job fails ("[sampler] walkers must be at least twice ..."): a 422 is wanted."""
    ha, hb = upload(client, A, "at15.csv"), upload(client, B, "rest.csv")
    config = tomllib.loads(two(ha, hb, "hash"))
    config["sampler"].update(walkers=4, max_steps=10, map_starts=1)
    r = client.post(
        "/v1/fits",
        json={"config": config, "data": [{"hash": ha, "name": "at15.csv"}, {"hash": hb, "name": "rest.csv"}]},
    )
    if r.status_code == 202:
        wait_job(client, r.json()["id"], timeout=600)
    assert r.status_code == 422, r.text


def test_full_model_quadrature_is_counted(client):
    """The full model's gonio rows take the smooth model's slit and cone settings
    (bsdflab.fit.gonio_instrument): at their maximum (63 x 64 x 64 nodes) a run within the
    walker-step and emulator limits unweighted (16 x 1024 steps, 5^3 + 4 solves) is refused,
    each weighed by the quadrature over its default, as the smooth model's."""
    config = copy.deepcopy(FULL)
    config["model"].update(bandwidth_nodes=63, cone_nodes=64, cone_azimuths=64)
    config["instrument"].update(acceptance_deg=2.0, bandwidth_nm=5.0)
    config["sampler"].update(walkers=16, max_steps=1 << 10, map_starts=1)
    r = post(client, full_body(client, config))
    assert r.status_code == 422 and "quadrature" in r.text, r.text


def test_full_model_free_instrument_terms_are_emulator_axes(client):
    """A free offset, cone and slit are axes of the full model's emulator: 8 nodes over 3
    structure parameters (512 solves) pass, over those and the 3 terms (8^6) are refused;
    one free cone at the example's 5 nodes (5^4 + 4 solves) is accepted."""
    config = copy.deepcopy(FULL)
    config["model"].update(emulator_nodes=8)
    assert post(client, full_body(client, config)).status_code == 202
    wide = {"prior": "uniform", "low": 0.0, "high": 2.0}
    config["instrument"].update(angle_offset_deg=wide, acceptance_deg=wide, bandwidth_nm=wide)
    r = post(client, full_body(client, config))
    assert r.status_code == 422 and "emulator_nodes" in r.text, r.text
    config = copy.deepcopy(FULL)
    config["instrument"].update(acceptance_deg=wide)
    r = post(client, full_body(client, config))
    assert r.status_code == 202, r.text
