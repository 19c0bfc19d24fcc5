"""The validation registry and `bsdflab validate`: one implementation of each check.

The suite runs `bsdflab validate --level quick` once (a real process writing a real report)
and then holds every registered check to its own verdict there (one test per check,
parametrised over the registry), validates results.json against the package's JSON schema,
opens the HTML in headless Chromium, and proves the checks have power by injecting
deliberately broken models through the registry (they must fail, and the exit status must
be non-zero).
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from bsdflab.validation import FAMILIES, LEVELS, REGISTRY, SCHEMA_PATH, Check, effort, load_checks
from bsdflab.validation.runner import missing_requirements, run_check

load_checks()
HERE = Path(__file__).parent
PLUGIN = HERE.parent / "support" / "validation_plugins" / "broken_models.py"
BSDFLAB = [sys.executable, "-m", "bsdflab.cli.main", "validate"]


def _run(args, tmp, timeout=900):
    env = dict(os.environ, BSDFLAB_CACHE_DIR=str(tmp / "cache"))
    return subprocess.run([*BSDFLAB, *args], capture_output=True, text=True, timeout=timeout, env=env)


# quick_report: tests/validation/conftest.py (one quick run; only this file reads it)


def _marks(check: Check):
    return [pytest.mark.mitsuba] if "mitsuba" in check.requires else []


@pytest.mark.parametrize("name", [pytest.param(c.name, marks=_marks(c), id=c.name) for c in REGISTRY])
def test_registered_check_passes_at_quick(name, quick_report):
    """Each registered check, as run by the report: pass (or, for a study, ran)."""
    check = REGISTRY[name]
    missing = missing_requirements(check)
    # Every built-in check's requirement is a dependency: missing is a broken setup, not a skip.
    assert not missing, f"the test environment lacks {', '.join(missing)} (pyproject.toml installs it)"
    _, doc, _ = quick_report
    row = next(r for r in doc["checks"] if r["name"] == name)
    assert row["status"] == ("study" if check.kind == "study" else "pass"), f"{name}: {row['message']}"
    assert row["seed"] == check.seed and row["effort"] == check.effort["quick"]
    assert row["tolerance"]["derivation"] == check.tolerance


def test_report_has_every_check_and_validates_against_the_schema(quick_report):
    import jsonschema

    proc, doc, out = quick_report
    jsonschema.Draft202012Validator(json.loads(SCHEMA_PATH.read_text())).validate(doc)
    assert [r["name"] for r in doc["checks"]] == REGISTRY.names()
    assert doc["level"] == "quick" and doc["performance"] == []  # benchmarks are optional at quick
    assert proc.returncode == doc["exit_status"] == 0, proc.stdout[-2000:]
    html = (out / "index.html").read_text()
    for name in REGISTRY.names():
        assert f'id="{name}"' in html
    for family in FAMILIES:
        assert f'id="family-{family}"' in html
    assert 'id="approximations"' in html and "data:image/png;base64," in html
    assert not re.search(r"""(src|href)=["']https?://""", html), "the report must not need the network"
    prov = doc["provenance"]
    assert prov["versions"]["bsdflab"] and prov["versions"]["tmm"] and prov["versions"]["colour-science"]
    assert "target_compile_options" in prov["core_build"]


def test_schema_rejects_a_malformed_document(quick_report):
    import jsonschema

    _, doc, _ = quick_report
    schema = json.loads(SCHEMA_PATH.read_text())
    bad = json.loads(json.dumps(doc))
    bad["checks"][0]["status"] = "maybe"
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(bad, schema)
    del bad["checks"][0]["tolerance"]
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(bad, schema)


def test_report_opens_in_headless_chromium_without_console_errors(quick_report, tmp_path):
    import playwright.sync_api as playwright  # a test dependency; a real browser, never skipped

    assert Path("/usr/bin/chromium").exists(), "Debian's chromium is missing (dev.sh installs it)"
    _, _, out = quick_report
    errors = []
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.on("request", lambda r: errors.append(f"network request {r.url}")
                if not r.url.startswith(("file:", "data:")) else None)
        page.goto((out / "index.html").as_uri())
        assert "validation report" in page.inner_text("header h1")
        broken = page.evaluate("[...document.images].filter(i => !(i.complete && i.naturalWidth > 0)).length")
        shot = Path(os.environ.get("BSDFLAB_TEST_FIGURES", tmp_path)) / "validation_report.png"
        shot.parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(shot))
        browser.close()
    assert not errors, errors
    assert broken == 0
    assert shot.stat().st_size > 10_000


def test_broken_models_injected_through_the_registry_turn_rows_red(tmp_path):
    """Diffuse 3 % high (furnace, Mitsuba), a skewed sampler (chi-square), the double-counted
    film phase (tmm): each row fails, and the exit status is 1."""
    out = tmp_path / "report"
    proc = _run(["--plugin", str(PLUGIN), "--only", "broken", "--out", str(out), "--quiet"], tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    doc = json.loads((out / "results.json").read_text())
    assert doc["exit_status"] == 1 and len(doc["checks"]) >= 3
    html = (out / "index.html").read_text()
    for row in doc["checks"]:
        assert row["status"] == "fail", (row["name"], row["message"])
        assert re.search(rf'<tr class="row fail" id="{re.escape(row["name"])}"', html)
    assert "FAILED" in html


def test_a_check_that_raises_is_an_error_row_not_a_crash():
    def run(ctx):
        raise RuntimeError("boom")

    c = Check(name="basic/raises", family="basic", title="t", model="m", reference="r", statistic="s",
              tolerance="t", run=run, effort=effort({}, {}))
    result = run_check(c, "quick")
    assert result.status == "error" and "boom" in result.message and not result.passed


def test_registry_rejects_bad_definitions_and_levels():
    with pytest.raises(ValueError, match="family"):
        Check(name="x", family="nope", title="", model="", reference="r", statistic="s", tolerance="t",
              run=lambda ctx: None, effort=effort({}, {}))
    with pytest.raises(ValueError, match="effort lacks"):
        Check(name="x", family="basic", title="", model="", reference="r", statistic="s", tolerance="t",
              run=lambda ctx: None, effort={"quick": {}})
    with pytest.raises(ValueError, match="already registered"):
        REGISTRY.add(REGISTRY[REGISTRY.names()[0]])
    with pytest.raises(ValueError, match="level"):
        run_check(REGISTRY[REGISTRY.names()[0]], "fast")
    assert set(LEVELS) == {"quick", "standard", "full"}
    assert REGISTRY.select("films/tmm/*") and not REGISTRY.select("no-such-check")


def test_cli_bad_input_exits_2(tmp_path):
    proc = _run(["--only", "no-such-check", "--out", str(tmp_path / "r")], tmp_path, timeout=120)
    assert proc.returncode == 2 and "matches no check" in proc.stderr
    assert not (tmp_path / "r").exists()
