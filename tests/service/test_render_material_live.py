"""Issue 33, item 4, end to end against a real ``bsdflab serve`` (worker processes): the
table `bsdflab tabulate` put in the cache is the one a render job uses (its summary says
so, and the cached file is untouched), and the page renders and tabulates the material
being edited (Chromium)."""
from __future__ import annotations

import json
import os
import shutil

import httpx2 as httpx
import pytest
from playwright import sync_api as playwright

from support.cli import cli
from support.liveness import HANG_MS, HANG_S
from support.service_process import ServiceProcess, wait_state

GRID = {"n_theta_i": 4, "n_theta_o": 8, "n_phi": 5}
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("cli-cache")


@pytest.fixture(scope="module")
def server(tmp_path_factory, cache):
    s = ServiceProcess(tmp_path_factory.mktemp("material-live"), cache_dir=cache)
    yield s
    s.stop()


def test_a_render_job_reuses_the_clis_cached_table(server, cache):
    """`bsdflab tabulate` (method auto: adding-doubling for this layered preset) fills the
    cache; the server shares it, so a render of the same tabulated material reports the
    table from_cache and the file keeps its bytes and time. Mutation caught (run once):
    render jobs tabulating into their artefact folder again: from_cache false, a second file."""
    made = cli("tabulate", "--preset", "xenopeltis-thin-film", "--theta-i", "4", "--theta-o", "8", "--phi", "5",
               "--rel-error", "0.5", "--cache-dir", str(cache), "--quiet")
    assert made.returncode == 0, made.stderr
    files = sorted(cache.glob("*.exr"))
    assert len(files) == 1 and "adding-doubling" in made.stdout, made.stdout
    before = (files[0].read_bytes(), files[0].stat().st_mtime_ns)
    material = {"type": "tabulated", "model": {"preset": "xenopeltis-thin-film"}, "grid": GRID, "rel_error": 0.5}
    r = httpx.post(f"{server.url}/v1/renders", json={"scene": "sphere", "options": {"variant": "full",
                   "material": material}, "width": 16, "height": 9, "spp": 1}, timeout=HANG_S)
    assert r.status_code == 202, r.text
    assert wait_state(server.url, r.json()["id"], ("done", "failed", "cancelled"))["state"] == "done"
    summary = httpx.get(f"{server.url}/v1/renders/{r.json()['hash']}").json()["summary"]
    assert json.loads(summary["tables"]) == [{"hash": files[0].stem, "method": "adding-doubling",
                                              "from_cache": True, "target_met": True}]
    assert sorted(cache.glob("*.exr")) == files and (files[0].read_bytes(), files[0].stat().st_mtime_ns) == before
    assert not list((server.data_dir / "artefacts").glob(f"{files[0].stem}*"))   # no second copy
    # the table the CLI made is also a table of the server's (by its hash)
    assert httpx.get(f"{server.url}/v1/tables/{files[0].stem}").status_code == 200


def test_the_page_renders_and_tabulates_the_edited_material(server):
    """Move the film slider, render with "the material being edited", tabulate it: the
    render request carries the edited film thickness (a tabulated model, the preset
    being layered), the table request the same model spec, and both finish on the page.
    Mutation caught (run once): the render card sending the scene's own material (the
    request's options without the edit)."""
    if not os.path.exists(CHROMIUM):
        pytest.fail("Debian's chromium is required (apt-get install chromium; dev.sh installs it)")
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1440, "height": 1400})
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(server.url + "/")
        page.wait_for_function("+(document.body.dataset.lobeUpdates || 0) >= 1", timeout=HANG_MS)
        page.select_option("#preset", "xenopeltis-thin-film")
        page.fill("#film_thickness_nm", "555")
        page.select_option("#scene", "sphere")
        page.select_option("#variant", "thin-film+bump")
        page.select_option("#material", "edited")
        page.select_option("#size", "160x90")
        page.select_option("#spp", "4")
        with page.expect_request(lambda r: r.url.endswith("/v1/renders") and r.method == "POST") as sent:
            page.click("#render-button")
        body = sent.value.post_data_json
        material = body["options"]["material"]
        assert material["type"] == "tabulated", body
        assert material["model"] == {"preset": "xenopeltis-thin-film",
                                     "overrides": {**material["model"]["overrides"], "film_thickness_nm": 555}}
        page.wait_for_selector("#render-image:not([hidden])", timeout=HANG_MS)
        page.wait_for_function("document.getElementById('render-image').naturalWidth === 160", timeout=HANG_MS)

        page.select_option("#tables-grid", "4x8x5")
        with page.expect_request(lambda r: r.url.endswith("/v1/tables") and r.method == "POST") as table_sent:
            page.click("#tables-button")
        table_body = table_sent.value.post_data_json
        assert table_body["preset"] == "xenopeltis-thin-film" and table_body["grid"] == GRID
        assert table_body["overrides"]["film_thickness_nm"] == 555
        page.wait_for_function("document.body.dataset.tableHash", timeout=HANG_MS)
        shown = page.evaluate("document.body.dataset.tableHash")
        method = page.text_content("#tables-result dd[data-field='method']")
        browser.close()
    assert not errors, errors
    info = httpx.get(f"{server.url}/v1/tables/{shown}").json()
    assert info["meta"].get("method") == method == "adding-doubling"
    assert info["model"] == httpx.post(f"{server.url}/v1/bsdf/lobe", json={
        "preset": table_body["preset"], "overrides": table_body["overrides"], "points": 3, "resolution": 3,
        "view": "plane"}, timeout=HANG_S).json()["model"]
