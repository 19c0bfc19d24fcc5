"""The order ``./dev.sh test`` hands test files to pytest-xdist's workers (``--dist loadfile
--no-loadscope-reorder``: one file per worker at a time, so a module's fixtures are built
once, in collection order).

Files go longest first by their last measured time (tests/file_costs.json): the long files
start at once and the short ones fill in at the end, instead of a long file starting last on
one core while the others idle (xdist's own reorder, by number of tests, put the heaviest
single-test files last). A file not in the table counts as free. The order moves only the
finish, never a result: each test is independent of order.

Refresh the table after a suite run written with ``--junitxml=report.xml``:
``python tests/support/scheduling.py report.xml > tests/file_costs.json``.
"""
from __future__ import annotations

import json
import sys
import xml.etree.ElementTree as ET
from collections import defaultdict
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
COSTS = TESTS / "file_costs.json"


def file_of(nodeid: str) -> str:
    return nodeid.split("::", 1)[0]


def longest_first(items: list, costs: dict[str, float]) -> list:
    """``items`` with their files longest first; ties and each file's own order kept."""
    first: dict[str, int] = {}
    for n, item in enumerate(items):
        first.setdefault(file_of(item.nodeid), n)
    return sorted(items, key=lambda i: (-costs.get(file_of(i.nodeid), 0.0), first[file_of(i.nodeid)]))


def load_costs() -> dict[str, float]:
    return json.loads(COSTS.read_text()) if COSTS.exists() else {}


def costs_from_junit(xml_path: str, root: Path = TESTS.parent) -> dict[str, float]:
    """Seconds per test file (relative to ``root``) from a pytest --junitxml report
    (classname: the dotted module path, with a class name after it for a method)."""
    seconds: dict[str, float] = defaultdict(float)
    for case in ET.parse(xml_path).getroot().iter("testcase"):
        parts = case.get("classname", "").split(".")
        while parts and not (root / ("/".join(parts) + ".py")).exists():
            parts.pop()
        if parts:
            seconds["/".join(parts) + ".py"] += float(case.get("time", 0))
    return dict(sorted(((k, round(v, 1)) for k, v in seconds.items()), key=lambda kv: -kv[1]))


if __name__ == "__main__":
    json.dump(costs_from_junit(sys.argv[1]), sys.stdout, indent=0)
    sys.stdout.write("\n")
