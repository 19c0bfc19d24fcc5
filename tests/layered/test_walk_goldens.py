"""The layered walk's goldens (issue 34): eval, pdf, sample, estimate and eval_with_error of
both estimators on eleven stacks (tests/support/walk_goldens.py) must equal the committed
JSON bit for bit. A refactor of core/src/layered/ that changes any float fails here; a
deliberate estimator change regenerates the file (and says so in its commit).

Exact comparison, no tolerance: the walk draws its random numbers in program order and the
core is built with -ffp-contract=off (CMakeLists.txt), so the same source gives the same bits.
"""

import json
import math

from support.walk_goldens import GOLDENS, digest, generate


def _load():
    with open(GOLDENS) as f:
        return json.load(f)


def _same(a, b) -> bool:
    """Exact equality of nested JSON values; NaN equals NaN, +0.0 differs from -0.0."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        if math.isnan(a) or math.isnan(b):
            return math.isnan(a) and math.isnan(b)
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    return type(a) is type(b) and a == b


def test_committed_goldens_are_intact():
    doc = _load()
    assert digest(doc["goldens"]) == doc["sha256"]


def test_walk_reproduces_goldens_bit_for_bit():
    want = _load()["goldens"]
    got = generate()
    assert got.keys() == want.keys()
    differ = [f"{case}/{part}" for case in want for part in want[case] if not _same(got[case][part], want[case][part])]
    assert not differ, f"outputs changed: {differ}"
    assert digest(got) == digest(want)
