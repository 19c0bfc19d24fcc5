"""The Fit card in a real browser against a real ``bsdflab serve`` (worker processes): the
page uploads the chosen data file, submits the config, follows the job's events and shows
the study the API serves (issue 33: fits "work over HTTP and from the page")."""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import httpx2 as httpx
import pytest
from playwright import sync_api as playwright

from support.liveness import HANG_MS, HANG_S
from support.service_process import ServiceProcess, follow_events

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DATA = Path(__file__).resolve().parents[2] / "examples" / "fit" / "data.csv"
CONFIG = {"parameters": {"film_thickness_nm": {"prior": "normal", "mean": 430.0, "sd": 10.0},
                         "film_ior": {"prior": "normal", "mean": 1.83, "sd": 0.02}},
          "model": {"thickness_nodes": 1},
          "sampler": {"walkers": 8, "max_steps": 60, "check_every": 20, "map_starts": 1, "seed": 4},
          "appearance": {"draws": 4, "renders": 0, "angles_deg": [0, 30]}}


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = ServiceProcess(tmp_path_factory.mktemp("fits-live"))
    yield s
    s.stop()


def test_a_fit_over_http_in_a_worker_process(server):
    """Upload, submit and follow a fit's server-sent events on the real server (jobs in
    worker processes, which register the kind by name): the progress never goes back, the
    last event is done, and the study's summary is the fit of the uploaded rows."""
    up = httpx.post(f"{server.url}/v1/fits/datasets", params={"name": "data.csv"}, content=DATA.read_bytes(),
                    headers={"Content-Type": "application/octet-stream"}, timeout=HANG_S)
    assert up.status_code == 200, up.text
    body = {"config": {**CONFIG, "sampler": {**CONFIG["sampler"], "seed": 9}},
            "data": [{"hash": up.json()["hash"], "name": "data.csv"}]}
    r = httpx.post(f"{server.url}/v1/fits", json=body, timeout=HANG_S)
    assert r.status_code == 202, r.text
    events = follow_events(server.url, r.json()["id"], timeout=600)
    progress = [job["progress"] for name, job in events if name == "progress"]
    assert progress == sorted(progress) and events[-1][0] == "done", events
    summary = httpx.get(f"{server.url}/v1/fits/{events[-1][1]['hash']}/files/summary.json", timeout=HANG_S).json()
    assert summary["rows"] == up.json()["summary"]["rows"] == 189 and summary["sampler"] == "emcee"


def test_a_fit_from_the_page(server):
    """The card's figures are the API's: the posterior means it prints are summary.json's
    (to the 5 digits it shows), its corner plot is the study's corner.png, and every link
    is a file the API lists. Mutation caught: the card printing the MAP instead of the mean."""
    if not os.path.exists(CHROMIUM):
        pytest.fail("Debian's chromium is required (apt-get install chromium; dev.sh installs it)")
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1440, "height": 1100})
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(server.url + "/")
        page.set_input_files("#fit-data", str(DATA))
        page.fill("#fit-config", json.dumps(CONFIG))
        page.click("#fit-button")
        page.wait_for_selector("#fit-corner:not([hidden])", timeout=HANG_MS)
        page.wait_for_function("document.getElementById('fit-corner').naturalWidth > 0", timeout=HANG_MS)
        h = page.evaluate("document.getElementById('fit-out').dataset.hash")
        shown = page.inner_text("#fit-summary")
        links = page.eval_on_selector_all("#fit-files a", "as => as.map(a => a.getAttribute('href'))")
        corner_src = page.evaluate("document.getElementById('fit-corner').src")
        browser.close()
    assert not errors, errors
    info = httpx.get(f"{server.url}/v1/fits/{h}", timeout=HANG_S).json()
    assert info["state"] == "done" and info["job"]["state"] == "done", info
    assert sorted(links) == sorted(f"/v1/fits/{h}/files/{name}" for name in info["files"])
    summary = httpx.get(f"{server.url}/v1/fits/{h}/files/summary.json", timeout=HANG_S).json()
    for name in summary["free"]:
        assert f"{name} = {summary['posterior_mean'][name]:.5g}" in shown, (name, shown)
    corner = httpx.get(corner_src, timeout=HANG_S)
    assert corner.status_code == 200 and corner.content == httpx.get(
        f"{server.url}/v1/fits/{h}/files/corner.png", timeout=HANG_S).content
