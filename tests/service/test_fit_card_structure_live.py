"""The Fit card's structure flow in Debian's Chromium against a real ``bsdflab serve``
(issue 33): a new user picks the structure example, chooses examples/fit/stack_data.csv and
runs it; picks the co-refinement and chooses its two files (each [[dataset]] names its file,
the page sends the upload's hash); pastes a long run and cancels it. The assertions are on
what the card shows, compared with the study's own summary.json as the API serves it.

Each fit is the example's (16-20 walkers, 200 steps, seconds of sampling); the cancelled one
is stopped once its sampling shows on the bar."""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
from pathlib import Path

import httpx2 as httpx
import numpy as np
import pytest
from playwright import sync_api as playwright

from support.liveness import HANG_MS, HANG_S
from support.service_process import ServiceProcess

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
KEY = "fit-card-secret"
ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = {e["id"]: e for e in json.loads((ROOT / "service" / "static" / "fit_examples.json").read_text())}
# the card prints 5 significant digits (toPrecision(5)): within half a unit of the 5th digit
RTOL = 5e-5
# the card's status while the job runs: "running · 43% · 3.1 s"
RUNNING = re.compile(r"^running · (\d+)% · ")
# every text #fit-status shows, in order (a MutationObserver: no polling, nothing missed)
WATCH = """() => { window.fitStatuses = [];
  new MutationObserver(() => window.fitStatuses.push(document.getElementById('fit-status').textContent))
    .observe(document.getElementById('fit-status'), {childList: true, characterData: true, subtree: true}); }"""

STUDY_OR_STOP = """() => { const status = document.getElementById('fit-status').textContent;
  return Boolean(document.getElementById('fit-out').dataset.hash) || (!document.getElementById('fit-button').disabled
    && !status.startsWith('done in') && !status.startsWith('from the artefact store')); }"""

# the SHA-256 of what an <img> shows, fetched by the page (a blob URL when the page has a key)
SHA256 = """async (id) => { const bytes = await (await fetch(document.getElementById(id).src)).arrayBuffer();
  return [...new Uint8Array(await crypto.subtle.digest('SHA-256', bytes))]
    .map(x => x.toString(16).padStart(2, '0')).join(''); }"""


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = ServiceProcess(tmp_path_factory.mktemp("fit-card"))
    yield s
    s.stop()


@pytest.fixture(scope="module")
def browser():
    """One Chromium for the module (a launch costs ~2 CPU-s); each test has a context of its
    own (its localStorage: a typed key stays in its test), as browser.new_page gave it."""
    if not os.path.exists(CHROMIUM):
        pytest.fail("Debian's chromium is required (apt-get install chromium; dev.sh installs it)")
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield browser
        browser.close()


@pytest.fixture
def page(browser, server):
    yield from browse(browser, server)


def browse(browser, server, key: str | None = None):
    """The page in a fresh context of ``browser`` (with ``key`` typed into its API key box);
    no page error allowed."""
    context = browser.new_context(viewport={"width": 1440, "height": 1100})
    page = context.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(server.url + "/")
    if key:  # the page keeps a changed key (localStorage) and reloads with it (app.js)
        page.fill("#api-key", key)
        with page.expect_navigation():
            page.press("#api-key", "Enter")
        assert page.input_value("#api-key") == key
    page.evaluate(WATCH)
    yield page
    context.close()
    assert not errors, errors


def run_example(page, example: str | None, files: list[Path]) -> str:
    """Pick the example, choose the files, press Fit, wait for the study; its hash."""
    if example is not None:  # None: the config pasted into the card
        page.select_option("#fit-example", example)
        assert json.loads(page.input_value("#fit-config")) == EXAMPLES[example]["config"]
    page.set_input_files("#fit-data", [str(f) for f in files])
    page.click("#fit-button")
    # the study, or the card at rest with its message (a refusal, a failed job): no wait for a study never coming
    page.wait_for_function(STUDY_OR_STOP, timeout=HANG_MS)
    assert page.get_attribute("#fit-out", "data-hash"), page.inner_text("#fit-status")
    page.wait_for_function(
        "['fit-corner', 'fit-predictive'].every(id => document.getElementById(id).naturalWidth > 0)", timeout=HANG_MS
    )
    return page.evaluate("document.getElementById('fit-out').dataset.hash")


def get(server, path: str, key: str | None = None):
    r = httpx.get(server.url + path, headers={"X-API-Key": key} if key else {}, timeout=HANG_S)
    assert r.status_code == 200, (path, r.status_code, r.text)
    return r


def shown_table(page) -> list[list[str]]:
    return page.eval_on_selector_all(
        "#fit-parameters tbody tr", "rows => rows.map(r => [...r.cells].map(c => c.textContent))"
    )


def numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?", text)]


def check_study(page, server, h: str, key: str | None = None) -> dict:
    """What the card shows is the study's summary.json: each parameter's median, 90 %
    interval and MAP (to the 5 digits shown), the predictive checks' count, every warning
    word for word, the two figures byte for byte and every file the API lists."""
    info = get(server, f"/v1/fits/{h}", key).json()
    summary = get(server, f"/v1/fits/{h}/files/summary.json", key).json()
    rows = shown_table(page)
    assert [r[0] for r in rows] == summary["free"] == [p["parameter"] for p in summary["parameters"]]
    for shown, p in zip(rows, summary["parameters"], strict=True):
        assert shown[1] == p["unit"], (shown, p)
        got = numbers(shown[2]) + numbers(shown[3]) + numbers(shown[4])
        want = [p["median"], p["ci90_low"], p["ci90_high"], p["map"]]
        assert np.allclose(got, want, rtol=RTOL, atol=0), (shown, want)
    checks = summary["predictive_checks"]["series"]
    failed = [c for c in checks if c["flagged"]]
    assert f": {len(failed)} of {len(checks)} fail" in page.inner_text("#fit-checks")
    for c in failed:
        assert c["series"] in page.inner_text("#fit-checks"), c
    warnings = page.eval_on_selector_all("#fit-warnings li", "ls => ls.map(l => l.textContent)")
    assert warnings == [f"[{w['code']}] {w['message']}" for w in summary["warnings"]]
    links = page.eval_on_selector_all("#fit-files a", "as => as.map(a => a.getAttribute('href'))")
    assert sorted(links) == sorted(f"/v1/fits/{h}/files/{name}" for name in info["files"])
    for img, name in (("fit-corner", "corner.png"), ("fit-predictive", "predictive.png")):
        want = hashlib.sha256(get(server, f"/v1/fits/{h}/files/{name}", key).content).hexdigest()
        assert page.evaluate(SHA256, img) == want, name
    statuses = page.evaluate("window.fitStatuses")
    percents = [int(m.group(1)) for m in map(RUNNING.match, statuses) if m]
    assert percents == sorted(percents) and statuses[-1].startswith("done in "), statuses
    return summary


def test_a_structure_fit_from_the_page(page, server):
    """The structure example on examples/fit/stack_data.csv: the structure's and the
    instrument's parameters by name with their values (before: every value NaN, the
    snake's posterior means looked up in a summary that has none), the predictive checks,
    the warnings (a 200-step run: NOT_CONVERGED) and the figures. Mutation caught: the
    card printing posterior means for a structure study (NaN)."""
    h = run_example(page, "structure", [ROOT / "examples" / "fit" / "stack_data.csv"])
    summary = check_study(page, server, h)
    assert summary["free"] == [
        "film_thickness_nm",
        "gap_thickness_nm",
        "film_ior",
        "substrate_ior",
        "scale",
        "background",
        "angle_offset_deg",
        "bandwidth_nm",
    ]
    assert "NOT_CONVERGED" in [w["code"] for w in summary["warnings"]]  # 200 steps: the card says so
    assert page.inner_text("#fit-summary") == "structure study · 124 rows · datasets data · 200 steps (not converged)"
    assert "NaN" not in page.inner_text("#fit-out")
    # the same request again answers from the artefact store at once: the same study shown
    table = shown_table(page)
    page.click("#fit-button")
    page.wait_for_function(STUDY_OR_STOP, timeout=HANG_MS)
    assert page.inner_text("#fit-status") == "from the artefact store (fitted before)"
    assert page.get_attribute("#fit-out", "data-hash") == h and shown_table(page) == table


def test_a_co_refinement_from_the_page(page, server):
    """The co-refinement example: with one of its two files chosen the card refuses before
    uploading, naming the missing file; with both, each [[dataset]] goes to the server by
    its upload's hash (the file's SHA-256), and the card shows both datasets' instruments.
    Mutation caught: the card sending the data names (the server's 422 for a path)."""
    a, b = (ROOT / "examples" / "fit" / "corefine" / n for n in ("session_a.csv", "session_b.csv"))
    page.select_option("#fit-example", "corefine")
    page.set_input_files("#fit-data", [str(a)])
    page.click("#fit-button")
    assert (
        page.inner_text("#fit-status")
        == 'config.dataset[1].data "session_b.csv" is not one of the chosen files (session_a.csv)'
    )
    h = run_example(page, "corefine", [a, b])
    summary = check_study(page, server, h)
    sent = get(server, f"/v1/fits/{h}").json()["request"]
    assert [(e["name"], e["hash"]) for e in sent["config"]["dataset"]] == [
        ("a", hashlib.sha256(a.read_bytes()).hexdigest()),
        ("b", hashlib.sha256(b.read_bytes()).hexdigest()),
    ]
    assert all("data" not in e for e in sent["config"]["dataset"])
    assert summary["datasets"] == ["a", "b"] and {"a.scale", "b.scale"} <= set(summary["free"])
    assert page.inner_text("#fit-summary").startswith("structure study · 124 rows · datasets a, b · ")


def test_cancel_a_structure_fit_from_the_page(page, server):
    """A pasted long run (no stop before 50 000 steps) cancelled once its sampling shows on
    the bar: the card says cancelled with the job's reason, Fit is pressable again, the job
    is cancelled and no study was written."""
    config = json.loads(json.dumps(EXAMPLES["structure"]["config"]))
    config["sampler"].update(max_steps=50_000, tau_multiple=1e6)
    page.select_option("#fit-example", "structure")
    page.fill("#fit-config", json.dumps(config))
    page.set_input_files("#fit-data", str(ROOT / "examples" / "fit" / "stack_data.csv"))
    page.click("#fit-button")
    # the sampling stage begins at 25 % of the bar (bsdflab.fit.job.STAGES)
    page.wait_for_function(
        "/^running · (2[5-9]|[3-9]\\d)% · /.test(document.getElementById('fit-status').textContent)", timeout=HANG_MS
    )
    page.click("#fit-cancel")
    page.wait_for_function("document.getElementById('fit-status').textContent.startsWith('cancelled')", timeout=HANG_MS)
    assert page.inner_text("#fit-status") == "cancelled: sampling cancelled"
    assert page.is_enabled("#fit-button") and not page.is_visible("#fit-cancel")
    mine = get(server, "/v1/jobs?state=cancelled").json()["jobs"]
    assert len(mine) == 1 and mine[0]["kind"] == "fit", mine
    assert httpx.get(f"{server.url}/v1/fits/{mine[0]['hash']}/files/summary.json", timeout=HANG_S).status_code == 404


def test_a_structure_fit_with_an_api_key(tmp_path_factory, browser):
    """On a server that requires a key (BSDFLAB_API_KEY), the key typed into the page: the
    job is followed by polling (an EventSource cannot send the key; before: the card stopped
    silently), the figures are fetched with the key (before: broken images, 401) and a
    file opens with it. The run is the structure example cut to 40 steps, one slit, cone and
    azimuth node and the scale the only free instrument parameter (10 walkers): nothing here
    depends on the study's size (the full example: test_a_structure_fit_from_the_page), and
    its 8-parameter corner plot and 168 solves a row cost the worker seconds. Mutation
    caught: fit.js following the job by EventSource with a key (the card stops silently)."""
    server = ServiceProcess(tmp_path_factory.mktemp("fit-card-key"), env={"BSDFLAB_API_KEY": KEY})
    try:
        for page in browse(browser, server, KEY):
            config = json.loads(json.dumps(EXAMPLES["structure"]["config"]))
            config["sampler"].update(walkers=10, max_steps=40, check_every=20)
            config["model"].update(bandwidth_nodes=1, cone_nodes=1, cone_azimuths=1)
            config["instrument"].update(background=0.0, angle_offset_deg=0.0, bandwidth_nm=10.0)
            page.select_option("#fit-example", "structure")
            page.fill("#fit-config", json.dumps(config))
            h = run_example(page, None, [ROOT / "examples" / "fit" / "stack_data.csv"])
            summary = check_study(page, server, h, KEY)
            assert summary["steps"] == 40
            with page.expect_popup() as popup:
                page.click("#fit-files a:text-is('summary.json')")
            opened = popup.value.evaluate("fetch(location.href).then(r => r.json())")
            assert opened == summary
    finally:
        server.stop()


def test_the_card_refuses_before_uploading(page, server):
    """What the card says, before any upload, to a user who pastes the example's TOML or
    chooses a file no [[dataset]] names; nothing reaches the server (no upload)."""
    stack = ROOT / "examples" / "fit" / "stack_data.csv"
    uploads = get(server, "/v1/fits/datasets").json()["datasets"]
    page.fill("#fit-config", (ROOT / "examples" / "fit" / "stack.toml").read_text())
    page.set_input_files("#fit-data", str(stack))
    page.click("#fit-button")
    assert page.inner_text("#fit-status").startswith("the config is not JSON: ")
    assert page.inner_text("#fit-status").endswith(
        "(this looks like TOML: write its tables as JSON objects, or start from an example)"
    )
    page.select_option("#fit-example", "corefine")
    a, b = (ROOT / "examples" / "fit" / "corefine" / n for n in ("session_a.csv", "session_b.csv"))
    page.set_input_files("#fit-data", [str(a), str(b), str(stack)])
    page.click("#fit-button")
    assert page.inner_text("#fit-status") == 'no [[dataset]] names stack_data.csv (data = "<file name>")'
    assert get(server, "/v1/fits/datasets").json()["datasets"] == uploads
