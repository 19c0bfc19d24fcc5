"""The suite's own scheduling (tests/support/scheduling.py): files longest first, each
file's order kept, the cost table naming only files that exist, and the table's refresh
from a real pytest --junitxml report."""
from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
from types import SimpleNamespace

from support.scheduling import COSTS, TESTS, costs_from_junit, load_costs, longest_first


def _items(*nodeids):
    return [SimpleNamespace(nodeid=n) for n in nodeids]


def test_files_go_longest_first_and_keep_their_own_order():
    """Mutation: sorting by ascending cost, or by test name within a file, fails it."""
    items = _items("tests/a.py::t2", "tests/b.py::t1", "tests/a.py::t1", "tests/c.py::z", "tests/c.py::a")
    got = [i.nodeid for i in longest_first(items, {"tests/c.py": 9.0, "tests/a.py": 1.0})]
    assert got == ["tests/c.py::z", "tests/c.py::a", "tests/a.py::t2", "tests/a.py::t1", "tests/b.py::t1"]


def test_the_cost_table_names_only_files_that_exist():
    """A renamed or deleted test file must leave the table (refresh it: the module's docstring)."""
    costs = load_costs()
    assert len(costs) > 100 and all(v >= 0 for v in costs.values())
    missing = [p for p in costs if not (TESTS.parent / p).is_file()]
    assert not missing, f"{COSTS} names missing files {missing[:5]}: refresh it"


def test_the_table_is_refreshed_from_a_real_junit_report(tmp_path):
    """A real pytest run's --junitxml report of two files (one test a method of a class)
    gives each file the sum of its tests' times. Mutation: taking the class name as the
    file drops the method's time and fails it."""
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_one.py").write_text("import time\ndef test_a():\n    time.sleep(0.2)\n"
                                                    "def test_b():\n    pass\n")
    (tmp_path / "tests" / "test_two.py").write_text("import time\nclass TestK:\n    def test_c(self):\n"
                                                    "        time.sleep(0.3)\n")
    xml = tmp_path / "report.xml"
    subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--junitxml={xml}",
                    "--rootdir", str(tmp_path), "-c", "/dev/null", "tests"], cwd=tmp_path, check=True,
                   capture_output=True)
    times = {}
    for case in ET.parse(xml).getroot().iter("testcase"):
        times[case.get("name")] = float(case.get("time"))
    costs = costs_from_junit(str(xml), root=tmp_path)
    assert set(costs) == {"tests/test_one.py", "tests/test_two.py"}
    assert abs(costs["tests/test_one.py"] - round(times["test_a"] + times["test_b"], 1)) <= 0.05 + 1e-9
    assert abs(costs["tests/test_two.py"] - round(times["test_c"], 1)) <= 0.05 + 1e-9
    assert costs["tests/test_two.py"] >= 0.3 - 0.05
