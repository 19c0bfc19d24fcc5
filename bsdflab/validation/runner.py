"""Run checks at a level: each becomes a ``CheckResult`` (pass, fail, error or skipped)."""
from __future__ import annotations

import importlib.util
import time
import traceback
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsdflab.validation.registry import LEVELS, Check, Context, Figure, SkipCheck

STATUSES = ("pass", "fail", "error", "skipped", "study")


@dataclass
class CheckResult:
    check: Check
    level: str
    status: str
    value: float | None = None
    limit: float | None = None
    comparison: str = "<="
    message: str = ""
    details: dict[str, Any] = field(default_factory=dict)
    figures: list[Figure] = field(default_factory=list)
    duration_s: float = 0.0

    @property
    def passed(self) -> bool:
        """A study, a skipped check and a pass are not failures."""
        return self.status in ("pass", "skipped", "study")

    def to_dict(self) -> dict[str, Any]:
        c = self.check
        return {
            "name": c.name, "family": c.family, "title": c.title, "kind": c.kind,
            "model": c.model, "reference": c.reference, "statistic": c.statistic,
            "value": _number(self.value),
            "tolerance": {"limit": _number(self.limit), "comparison": self.comparison,
                          "derivation": c.tolerance},
            "status": self.status, "passed": self.passed, "seed": c.seed,
            "effort": _plain(c.effort[self.level]), "level": self.level,
            "duration_s": round(self.duration_s, 3), "message": self.message,
            "details": _plain(self.details), "figures": [f.caption for f in self.figures],
        }


def _number(x):
    if x is None:
        return None
    x = float(x)
    return x if np.isfinite(x) else str(x)  # JSON has no inf / nan


def _plain(x):
    """JSON-able copy of numbers, arrays, tuples and dicts."""
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return _plain(x.tolist())
    if isinstance(x, (np.floating, float)):
        return _number(x)
    if isinstance(x, (np.integer, np.bool_)):
        return x.item()
    return x


def missing_requirements(check: Check) -> list[str]:
    return [m for m in check.requires if importlib.util.find_spec(m) is None]


def run_check(check: Check, level: str = "quick") -> CheckResult:
    """Run one check; exceptions become status "error" with the traceback as message."""
    if level not in LEVELS:
        raise ValueError(f"level must be one of {LEVELS}, got {level!r}")
    missing = missing_requirements(check)
    if missing:
        return CheckResult(check, level, "skipped", message=f"needs {', '.join(missing)}")
    start = time.perf_counter()
    ctx = Context(level, dict(check.effort[level]), check.seed, None)
    try:
        ctx.model = check.make_model() if check.make_model is not None else None
        out = check.run(ctx)
    except SkipCheck as e:
        return CheckResult(check, level, "skipped", message=str(e), duration_s=time.perf_counter() - start)
    except Exception:  # the report shows the failure; the run goes on
        return CheckResult(check, level, "error", message=traceback.format_exc(limit=6),
                           figures=ctx.figures, duration_s=time.perf_counter() - start)
    status = ("study" if out.passed else "fail") if check.kind == "study" else ("pass" if out.passed else "fail")
    return CheckResult(check, level, status, out.value, out.limit, out.comparison, out.message,
                       out.details, ctx.figures, time.perf_counter() - start)


def run_checks(checks: Iterable[Check], level: str = "quick", progress: bool = True) -> list[CheckResult]:
    """Run checks in order with a progress bar over checks (tqdm, to stderr)."""
    checks = list(checks)
    results = []
    if progress:
        from tqdm import tqdm

        bar = tqdm(checks, desc=f"validate ({level})", unit="check", dynamic_ncols=True)
    else:
        bar = checks
    for check in bar:
        if progress:
            bar.set_postfix_str(check.name[-40:])
        results.append(run_check(check, level))
    return results
