"""`validate()`: run the checks of a level and write report/results.json and report/index.html."""
from __future__ import annotations

import json
import time
from pathlib import Path

from bsdflab.util.files import write_atomically
from bsdflab.validation.html import render_html
from bsdflab.validation.registry import LEVELS, REGISTRY, Check
from bsdflab.validation.runner import STATUSES, CheckResult, run_checks

SCHEMA_PATH = Path(__file__).with_name("results.schema.json")


def load_checks() -> None:
    """Import the check modules (they register themselves)."""
    from bsdflab.validation import checks  # noqa: F401


def results_document(results: list[CheckResult], level: str, only: str | None, provenance: dict,
                     performance: list[dict], duration_s: float) -> dict:
    summary = {s: sum(r.status == s for r in results) for s in STATUSES}
    summary["total"] = len(results)
    failed = any(not r.passed for r in results) or any(b["returncode"] not in (0, None) for b in performance)
    return {"schema_version": 1, "level": level, "only": only, "duration_s": round(duration_s, 2),
            "exit_status": 1 if failed else 0, "provenance": provenance, "summary": summary,
            "checks": [r.to_dict() for r in results], "performance": performance}


def validate(out_dir, level: str = "quick", only: str | None = None, checks: list[Check] | None = None,
             progress: bool = True, benchmarks: bool | None = None, argv: list[str] | None = None) -> dict:
    """Run ``checks`` (default: the registry, filtered by the glob ``only``) at ``level``,
    write ``out_dir``/results.json and index.html, and return the results document;
    its ``exit_status`` is 1 when a check failed or errored. ``benchmarks`` defaults to
    True except at the quick level."""
    from bsdflab.validation.performance import run_benchmarks
    from bsdflab.validation.provenance import provenance

    if level not in LEVELS:
        raise ValueError(f"level must be one of {', '.join(LEVELS)}, got {level!r}")
    if checks is None:
        load_checks()
        checks = REGISTRY.select(only)
        if not checks:
            raise ValueError(f"only={only!r} matches no check; names look like "
                             f"{', '.join(REGISTRY.names()[:3])}")
    start = time.perf_counter()
    results = run_checks(checks, level, progress=progress)
    run_bench = level != "quick" if benchmarks is None else benchmarks
    performance = run_benchmarks(level if level != "quick" else "standard", progress) if run_bench else []
    doc = results_document(results, level, only, provenance(level, argv), performance,
                           time.perf_counter() - start)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    text = json.dumps(doc, indent=1, allow_nan=False)
    write_atomically(out / "results.json", lambda tmp: Path(tmp).write_text(text))
    html = render_html(doc, results)
    write_atomically(out / "index.html", lambda tmp: Path(tmp).write_text(html, encoding="utf-8"))
    return doc
