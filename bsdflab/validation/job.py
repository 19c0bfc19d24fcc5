"""Job kind "validate": the validation report (``bsdflab validate``) as a job, so the HTTP
service runs it (``register_kind("validate", "bsdflab.validation.job")``).

Request (normalised)::

    {"level": "quick" | "standard" | "full", "only": null | "<glob or substring>",
     "families": ["<family>", ...] (absent: all), "benchmarks": false}

Artefacts in ``out_dir`` (content-addressed): ``<key>.json`` (the results document,
bsdflab/validation/results.schema.json) and ``<key>.html`` (the self-contained report).
Progress is the fraction of checks run; a cancel stops between checks.
"""
from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path
from typing import Any

from bsdflab import __version__
from bsdflab.util.files import write_atomically
from bsdflab.util.progress import JobCancelled
from bsdflab.validation.html import render_html
from bsdflab.validation.registry import FAMILIES, LEVELS, REGISTRY
from bsdflab.validation.report import load_checks, results_document
from bsdflab.validation.runner import run_check

FIELDS = {"level", "only", "families", "benchmarks"}


def _selected(request: dict[str, Any]):
    load_checks()
    return REGISTRY.select(request["only"], request.get("families"))


def normalise_families(families) -> list[str] | None:
    """None (every family) or the named families, deduplicated in registry order; an unknown
    name is a ValueError that lists the valid ones."""
    if families is None:
        return None
    if isinstance(families, str) or not isinstance(families, (list, tuple)) or not families:
        raise ValueError(f"families must be a non-empty list of family names: {', '.join(FAMILIES)}")
    unknown = [f for f in families if f not in FAMILIES]
    if unknown:
        raise ValueError(f"unknown validation families {', '.join(map(repr, unknown))}; "
                         f"valid: {', '.join(FAMILIES)}")
    return [f for f in FAMILIES if f in families]


def normalise(request: dict[str, Any]) -> dict[str, Any]:
    unknown = set(request) - FIELDS
    if unknown:
        raise ValueError(f"unknown validate request fields: {', '.join(sorted(unknown))}")
    level = request.get("level", "quick")
    if level not in LEVELS:
        raise ValueError(f"level must be one of {', '.join(LEVELS)}, got {level!r}")
    only = request.get("only")
    if only is not None and (not isinstance(only, str) or not only or len(only) > 200):
        raise ValueError("only must be a non-empty glob or substring of check names (at most 200 characters)")
    benchmarks = request.get("benchmarks", False)
    if not isinstance(benchmarks, bool):
        raise ValueError("benchmarks must be true or false")
    out = {"level": level, "only": only, "benchmarks": benchmarks}
    families = normalise_families(request.get("families"))
    if families is not None:  # absent when all: the keys of requests without families stay as they were
        out["families"] = families
    if not _selected(out):
        raise ValueError(f"only={only!r} in families {families or 'all'} matches no check; names look "
                         f"like {', '.join(REGISTRY.names()[:3])}")
    return out


def benchmark_level(request: dict[str, Any]) -> str | None:
    """The level whose benchmarks the request runs (quick has none: standard's), or None."""
    if not request.get("benchmarks"):
        return None
    return request["level"] if request["level"] != "quick" else "standard"


def key(request: dict[str, Any]) -> str:
    text = json.dumps({"kind": "validate", "bsdflab_version": __version__, "request": request}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def files(k: str) -> dict[str, str]:
    return {"json": f"{k}.json", "html": f"{k}.html"}


def _result(k: str, doc: dict[str, Any], from_cache: bool) -> dict[str, Any]:
    return {"hash": k, "files": files(k), "from_cache": from_cache, "summary": doc["summary"],
            "exit_status": doc["exit_status"], "level": doc["level"], "only": doc["only"],
            "duration_s": doc["duration_s"]}


def existing(request: dict[str, Any], out_dir: Path) -> dict[str, Any] | None:
    k = key(request)
    names = files(k)
    if not all((Path(out_dir) / n).is_file() for n in names.values()):   # the JSON is written last
        return None
    try:
        return _result(k, json.loads((Path(out_dir) / names["json"]).read_text()), True)
    except (OSError, ValueError, KeyError):
        return None


def run(request: dict[str, Any], out_dir: Path, progress, cancelled, runner=None) -> dict[str, Any]:
    from bsdflab.validation.performance import run_benchmarks
    from bsdflab.validation.provenance import provenance

    found = existing(request, out_dir)
    if found is not None:
        return found
    checks, level = _selected(request), request["level"]
    start, results = time.perf_counter(), []
    for i, check in enumerate(checks):
        if cancelled():
            raise JobCancelled(f"cancelled after {i} of {len(checks)} checks")
        results.append(run_check(check, level))
        progress((i + 1) / (len(checks) + (1 if request["benchmarks"] else 0)))
    performance = run_benchmarks(benchmark_level(request), False) if request["benchmarks"] else []
    doc = results_document(results, level, request["only"], provenance(level, ["bsdflab", "validate", "(job)"]),
                           performance, time.perf_counter() - start)
    k, out_dir = key(request), Path(out_dir)
    html = render_html(doc, results)
    write_atomically(out_dir / f"{k}.html", lambda tmp: Path(tmp).write_text(html, encoding="utf-8"))
    text = json.dumps(doc, indent=1, allow_nan=False)
    write_atomically(out_dir / f"{k}.json", lambda tmp: Path(tmp).write_text(text))
    return _result(k, doc, False)
