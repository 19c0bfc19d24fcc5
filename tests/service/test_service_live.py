"""End to end against a real `bsdflab serve` process (worker processes, SQLite, uvicorn):
a table and a render through HTTP with progress followed as server-sent events, the
downloads checked against the Python API; dedup of concurrent identical requests;
SIGKILL mid-job and restart; the page in Chromium (schemathesis: test_schema_fuzz_live.py)."""
from __future__ import annotations

import hashlib
import os
import shutil
import time
from concurrent.futures import ThreadPoolExecutor

import httpx2 as httpx
import numpy as np
import pytest
from playwright import sync_api as playwright

from bsdflab import presets
from bsdflab.jobs import get_kind
from bsdflab.jobs.render import build_scene
from bsdflab.render import read_exr, render
from bsdflab.tables import TableGrid, read_table, tabulate
from support.liveness import HANG_MS, HANG_S, wait_until
from support.service_process import ServiceProcess, follow_events, wait_state

# PFMC explicitly: the jobs' progress, restarts and kills need a table that takes walks
# (the default method, auto, makes this preset by adding-doubling in a moment)
SMALL_TABLE = {"preset": "xenopeltis-thin-film", "grid": {"n_theta_i": 2, "n_theta_o": 3, "n_phi": 3},
               "rel_error": 0.2, "min_samples": 64, "max_samples": 64, "seed": 5, "method": "pfmc"}
SMALL_RENDER = {"scene": "sphere", "options": {"variant": "diffuse"}, "width": 48, "height": 27, "spp": 2}


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = ServiceProcess(tmp_path_factory.mktemp("live"))
    yield s
    s.stop()


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def alive(pid: int) -> bool:
    """The process exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def direct_table(request: dict):
    """The same table from the Python API in this process."""
    r = get_kind("tabulate").normalise(request)
    return tabulate(presets.preset(request["preset"]), TableGrid.from_dict(r["grid"]), rel_error=r["rel_error"],
                    min_samples=r["min_samples"], max_samples=r["max_samples"], seed=r["seed"], method=r["method"],
                    progress=False)


def test_table_and_render_end_to_end(server, tmp_path):
    url = server.url
    # two identical requests at once share one job
    with ThreadPoolExecutor(2) as pool:
        first, second = pool.map(lambda _: httpx.post(f"{url}/v1/tables", json=SMALL_TABLE, timeout=HANG_S), range(2))
    assert first.status_code == second.status_code == 202, first.text
    job = first.json()
    assert second.json()["id"] == job["id"]
    events = follow_events(url, job["id"])
    assert events[-1][0] == "done" and events[-1][1]["progress"] == 1.0
    progress = [e["progress"] for name, e in events]
    assert progress == sorted(progress)
    info = httpx.get(f"{url}/v1/tables/{job['hash']}").json()
    table_file = httpx.get(f"{url}{info['links']['file']}")
    assert table_file.status_code == 200
    assert sha256(table_file.content) == sha256((server.cache_dir / f"{job['hash']}.exr").read_bytes())
    (tmp_path / "t.exr").write_bytes(table_file.content)
    table = read_table(tmp_path / "t.exr")             # verifies the file's content hash
    np.testing.assert_array_equal(table.values, direct_table(SMALL_TABLE).values)
    assert httpx.post(f"{url}/v1/tables", json=SMALL_TABLE).status_code == 200   # cached now

    r = httpx.post(f"{url}/v1/renders", json=SMALL_RENDER, timeout=HANG_S)
    assert r.status_code == 202, r.text
    done = wait_state(url, r.json()["id"], ("done", "failed", "cancelled"))
    assert done["state"] == "done", done
    info = httpx.get(f"{url}/v1/renders/{done['hash']}").json()
    assert info["state"] == "done" and info["summary"]["spp"] == "2"
    png = httpx.get(f"{url}{info['links']['png']}")
    exr = httpx.get(f"{url}{info['links']['exr']}")
    assert png.status_code == exr.status_code == 200 and png.content[:4] == b"\x89PNG"
    (tmp_path / "r.exr").write_bytes(exr.content)
    expected = render(build_scene(get_kind("render").normalise(SMALL_RENDER)), spp=2, seed=0, progress=False)
    np.testing.assert_array_equal(read_exr(tmp_path / "r.exr"), expected.mean.astype(np.float32))


def test_sigkill_mid_job_then_restart_completes_it(tmp_path):
    """The job is re-queued by the next server and completes; nothing half-written is left."""
    # long enough to be killed mid-way after the store records its start: 5 CPU-s (the kill
    # follows within milliseconds; the check below fails loudly if it ever finished first).
    # The table runs about 2.5 times (before the kill, after the restart, in this process):
    # 8192 walks took 12.5 CPU-s each. Mutation caught: a restart that gives a crashed job up
    # at once (``_recover`` without its attempts count) leaves it failed.
    request = {**SMALL_TABLE, "grid": {"n_theta_i": 4, "n_theta_o": 5, "n_phi": 3},
               "min_samples": 4096, "max_samples": 4096}
    first = ServiceProcess(tmp_path)
    try:
        job = httpx.post(f"{first.url}/v1/tables", json=request, timeout=HANG_S).json()
        wait_state(first.url, job["id"], ("running",))
        # until the store has recorded the start (``started``): a crash counts a start only
        # for a job the store shows running (its live progress can come first)
        deadline = time.monotonic() + HANG_S
        while True:
            seen = httpx.get(f"{first.url}/v1/jobs/{job['id']}").json()
            if seen["progress"] > 0 and seen["started"] is not None:
                break
            assert seen["state"] in ("queued", "running") and time.monotonic() < deadline, seen
            time.sleep(0.02)
        workers = first.children()
        assert workers, "the server runs its jobs in worker processes"
    finally:
        first.kill()
    # the workers die with their server (PR_SET_PDEATHSIG); one that outlived it would go on
    # and write the table (checked below)
    wait_until(lambda: not any(alive(pid) for pid in workers), f"end of the worker processes {workers}")
    artefact = tmp_path / "tables" / f"{job['hash']}.exr"   # the server's table cache (ServiceProcess)
    time.sleep(1.0)   # a worker that outlived its server would go on and write the table
    assert not artefact.exists(), "the job finished before the kill: make it longer"
    second = ServiceProcess(tmp_path)
    try:
        again = httpx.get(f"{second.url}/v1/jobs/{job['id']}").json()
        assert again["attempts"] == 1 and again["state"] in ("queued", "running")
        done = wait_state(second.url, job["id"], ("done", "failed", "cancelled"))
        assert done["state"] == "done", done
        # (the first table key of a fresh process takes seconds: bsdflab.jobs.tabulate.key)
        assert httpx.post(f"{second.url}/v1/tables", json=request, timeout=HANG_S).status_code == 200
    finally:
        second.stop()
    assert not [p.name for p in artefact.parent.iterdir() if p.name.startswith(".")]   # no temp files
    np.testing.assert_array_equal(read_table(artefact).values, direct_table(request).values)


# -- the page in a real browser --------------------------------------------------------------
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


def test_page_in_chromium(server, tmp_path):
    """The lobe explorer in a real browser: it plots what the API answers and shows the render.

    After a slider change, the polar plot's R curve equals the R column of the API's answer
    to the page's request (and the same request re-sent answers the same: seeded), and the
    screenshot's pixels where the render image sits have the colour of the PNG the API
    serves (mean over the box within 6 levels of 255). Mutations caught: the page plotting
    another channel (values[c + 1]) or a stale lobe; the render image not drawn (the box
    shows the page's background)."""
    if not os.path.exists(CHROMIUM):
        pytest.fail("Debian's chromium is required (apt-get install chromium; dev.sh installs it)")
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1440, "height": 1100})
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(server.url + "/")
        # one request at a time: the server has 2 computing slots and answers 429 beyond
        # them (BSDFLAB_HEAVY_CONCURRENCY), and the page does not retry; changing the quality
        # while the first lobe still computes lost that race under load
        page.wait_for_function("+(document.body.dataset.lobeUpdates || 0) >= 1", timeout=HANG_MS)
        page.wait_for_function("document.querySelectorAll('.swatch').length === 18", timeout=HANG_MS)
        page.select_option("#quality", "4")
        page.wait_for_function("+(document.body.dataset.lobeUpdates || 0) >= 2", timeout=HANG_MS)

        def lobe_red():
            return page.evaluate("document.getElementById('polar').data[0].r")

        def swatches():
            return page.eval_on_selector_all(".swatch", "cells => cells.map(c => c.dataset.colour)")

        before_lobe, before_swatches = lobe_red(), swatches()
        updates = int(page.evaluate("document.body.dataset.lobeUpdates"))
        with page.expect_response(lambda r: r.url.endswith("/v1/bsdf/lobe") and r.ok, timeout=HANG_MS) as lobe:
            page.fill("#film_thickness_nm", "650")     # a range input: fill sets it and fires input
        page.wait_for_function(f"+document.body.dataset.lobeUpdates > {updates}", timeout=HANG_MS)
        page.wait_for_function(f"document.querySelector('.swatch').dataset.colour !== '{before_swatches[0]}'",
                               timeout=HANG_MS)
        assert lobe_red() != before_lobe
        assert swatches() != before_swatches and len(swatches()) == 18
        shown = lobe_red()
        request = lobe.value.request.post_data_json
        assert request["overrides"]["film_thickness_nm"] == 650
        expected = [v[0] for v in lobe.value.json()["plane"]["values"]]
        assert np.allclose(np.asarray(shown, float), np.asarray(expected, float), rtol=0, atol=1e-12)
        # the same request answers the same (seeded): what the page shows is the API's answer
        again = httpx.post(server.url + "/v1/bsdf/lobe", json=request, timeout=120).json()
        assert [v[0] for v in again["plane"]["values"]] == expected

        page.select_option("#scene", "sphere")
        page.select_option("#variant", "diffuse")
        page.select_option("#material", "table")   # the variant's own base colour (test_render_material_live.py)
        page.select_option("#size", "160x90")
        page.select_option("#spp", "4")
        page.click("#render-button")
        page.wait_for_selector("#render-image:not([hidden])", timeout=HANG_MS)
        page.wait_for_function("document.getElementById('render-image').naturalWidth === 160", timeout=HANG_MS)
        page.evaluate("window.scrollTo(0, 0)")
        src = page.evaluate("document.getElementById('render-image').src")
        box = page.locator("#render-image").bounding_box()
        shot = tmp_path / "service.png"
        page.screenshot(path=str(shot), full_page=True)
        browser.close()
    assert not errors, errors
    _assert_screenshot_shows(shot, box, src)


def _assert_screenshot_shows(shot, box, src):
    """The screenshot's pixels inside the image box have the mean colour of the PNG the
    API serves at src (within 6 levels of 255: the browser scales it)."""
    from io import BytesIO

    from PIL import Image

    served = np.asarray(Image.open(BytesIO(httpx.get(src, timeout=HANG_S).content)).convert("RGB"), float)
    seen = np.asarray(Image.open(shot).convert("RGB"), float)
    x0, y0 = int(box["x"]) + 2, int(box["y"]) + 2      # inside the box: no border or antialiased edge
    x1, y1 = int(box["x"] + box["width"]) - 2, int(box["y"] + box["height"]) - 2
    region = seen[y0:y1, x0:x1]
    assert region.size and served.std() > 5           # a picture, not a flat colour
    assert np.abs(region.mean(axis=(0, 1)) - served.mean(axis=(0, 1))).max() < 6, (
        region.mean(axis=(0, 1)), served.mean(axis=(0, 1)))
