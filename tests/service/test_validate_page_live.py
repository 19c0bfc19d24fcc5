"""The page's Validate card in Chromium against a real ``bsdflab serve``: the families come
from GET /v1/validations/families, ticking one and pressing "Run validation" starts a job
(POST /v1/validations with that family), the card follows it to the end and opens the
self-contained HTML report, which shows the family's check as passed; no console errors."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from playwright import sync_api as playwright

from support.liveness import HANG_MS
from support.service_process import ServiceProcess

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = ServiceProcess(tmp_path_factory.mktemp("validate-page"))
    yield s
    s.stop()


def test_validate_card_runs_a_quick_validation_and_opens_the_report(server, tmp_path):
    if not Path(CHROMIUM).exists():
        pytest.fail("Debian's chromium is required (apt-get install chromium; dev.sh installs it)")
    errors, posted = [], []
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        page.on("pageerror", lambda e: errors.append(str(e)))
        # the card's own requests must all succeed (the lobe explorer's are test_service_live.py's)
        page.on(
            "response",
            lambda r: (
                errors.append(f"{r.status} {r.url}")
                if r.status >= 400 and ("/validations" in r.url or "/v1/jobs" in r.url)
                else None
            ),
        )
        page.on(
            "request",
            lambda r: (
                posted.append(r.post_data_json) if r.method == "POST" and r.url.endswith("/v1/validations") else None
            ),
        )
        page.goto(server.url + "/")
        page.wait_for_selector("#validate-families input[value='fit']", timeout=HANG_MS)
        labels = page.eval_on_selector_all("#validate-families input", "boxes => boxes.map(b => b.value)")
        assert {"solvers", "coverage", "fit", "measured", "export", "service"} <= set(labels), labels
        page.select_option("#validate-level", "quick")
        page.check("#validate-families input[value='fit']")
        page.click("#validate-button")
        page.wait_for_selector("#validate-report:not([hidden])", timeout=HANG_MS)
        assert posted == [{"level": "quick", "families": ["fit"]}], posted
        status = page.inner_text("#validate-status")
        assert status.startswith("done: 1 pass, 0 fail"), status
        page.locator("#validate-card").screenshot(
            path=str(Path(os.environ.get("BSDFLAB_TEST_FIGURES", tmp_path)) / "validate_card.png")
        )
        with page.expect_popup() as opened:
            page.click("#validate-report")
        report = opened.value
        report.wait_for_load_state()
        assert "validation report" in report.inner_text("header h1")
        row = report.locator('tr[id="fit/recovery/thin-film"]')
        assert row.count() == 1 and "pass" in (row.get_attribute("class") or ""), report.content()[:2000]
        browser.close()
    assert not errors, errors
