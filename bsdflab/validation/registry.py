"""The registry of validation checks: one definition per check, run by pytest and the report.

A ``Check`` names what is tested (model), against what (reference), the statistic, its
tolerance and how that tolerance was derived, and the effort per level. Its ``run`` gets a
``Context`` (the level's effort, the seed, the model built by ``make_model``, a place for
figures) and returns an ``Outcome``. ``with_model`` gives the same check with another model:
that is how a user checks their own BSDF, and how the test suite proves the checks have
power (a deliberately broken model must fail them).
"""
from __future__ import annotations

import fnmatch
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

LEVELS = ("quick", "standard", "full")
FAMILIES = ("basic", "rough", "films", "layered", "tables", "renderer", "solvers", "coverage", "fit",
            "measured", "export", "service")
KINDS = ("check", "study")  # a study reports numbers (e.g. colour errors) without a limit


class SkipCheck(Exception):  # noqa: N818 -- a verdict, not an error
    """Raised by a check's ``run`` when what it needs is absent at run time (e.g. a
    Blender interpreter): the row is "skipped" with this message."""


@dataclass
class Figure:
    caption: str
    png_base64: str


@dataclass
class Outcome:
    """What a check measured. ``passed`` compares ``value`` with ``limit`` (``comparison``
    says how, e.g. "<="); ``details`` holds further numbers for the report and the JSON."""

    passed: bool
    value: float
    limit: float
    comparison: str = "<="
    message: str = ""
    details: dict[str, Any] = field(default_factory=dict)


@dataclass
class Context:
    level: str
    effort: dict[str, Any]
    seed: int
    model: Any
    figures: list[Figure] = field(default_factory=list)

    def figure(self, fig, caption: str) -> None:
        """Embed a matplotlib Figure (rendered now, to PNG)."""
        from bsdflab.validation.figures import to_base64_png

        self.figures.append(Figure(caption, to_base64_png(fig)))

    def png(self, path, caption: str) -> None:
        """Embed a PNG file written by an existing plotting helper."""
        import base64
        from pathlib import Path

        self.figures.append(Figure(caption, base64.b64encode(Path(path).read_bytes()).decode("ascii")))


@dataclass(frozen=True)
class Check:
    name: str                                  # unique, "family/what"
    family: str
    title: str
    model: str                                 # the model under test, in words
    reference: str                             # the independent reference
    statistic: str                             # what ``Outcome.value`` is
    tolerance: str                             # how ``Outcome.limit`` was derived
    run: Callable[[Context], Outcome]
    effort: dict[str, dict[str, Any]]          # level -> parameters of run
    make_model: Callable[[], Any] | None = None
    seed: int = 0
    requires: tuple[str, ...] = ()             # importable modules needed (else skipped)
    kind: str = "check"

    def __post_init__(self):
        if self.family not in FAMILIES:
            raise ValueError(f"family must be one of {FAMILIES}, got {self.family!r}")
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")
        missing = [lv for lv in LEVELS if lv not in self.effort]
        if missing:
            raise ValueError(f"check {self.name!r}: effort lacks levels {missing}")

    def with_model(self, make_model: Callable[[], Any], name: str | None = None,
                   model: str | None = None) -> Check:
        """The same check (statistic, tolerance, effort, seed) on another model."""
        return replace(self, make_model=make_model, name=name or self.name,
                       model=model or self.model)


class Registry:
    def __init__(self) -> None:
        self._checks: dict[str, Check] = {}

    def add(self, check: Check) -> Check:
        if check.name in self._checks:
            raise ValueError(f"a check named {check.name!r} is already registered")
        self._checks[check.name] = check
        return check

    def check(self, **fields) -> Callable[[Callable[[Context], Outcome]], Callable[[Context], Outcome]]:
        """Decorator: register the decorated ``run`` function with these Check fields."""
        def register(run):
            self.add(Check(run=run, **fields))
            return run
        return register

    def __iter__(self):
        return iter(self._checks.values())

    def __len__(self) -> int:
        return len(self._checks)

    def __getitem__(self, name: str) -> Check:
        return self._checks[name]

    def names(self) -> list[str]:
        return list(self._checks)

    def select(self, pattern: str | None = None, families=None) -> list[Check]:
        """Checks whose name matches the glob ``pattern`` (or contains it as a substring),
        of the ``families`` named (None: all)."""
        chosen = [c for c in self if families is None or c.family in families]
        if not pattern:
            return chosen
        return [c for c in chosen if fnmatch.fnmatch(c.name, pattern) or pattern in c.name]

    def families(self) -> dict[str, int]:
        """Checks per family, every family listed (in FAMILIES order)."""
        return {f: sum(c.family == f for c in self) for f in FAMILIES}


REGISTRY = Registry()


def effort(quick: dict, standard: dict, full: dict | None = None) -> dict[str, dict]:
    """Effort table of a check; ``full`` defaults to ``standard``."""
    return {"quick": quick, "standard": standard, "full": full if full is not None else standard}
