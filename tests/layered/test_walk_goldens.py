"""The layered walk's goldens (issue 34): eval, pdf, sample, estimate and eval_with_error of
both estimators on eleven stacks (tests/support/walk_goldens.py) must equal the committed
JSON bit for bit. A refactor of core/src/layered/ that changes any float fails here; a
deliberate estimator change regenerates the file (and says so in its commit).

Exact comparison, no tolerance: the walk draws its random numbers in program order and the
core is built with -ffp-contract=off (CMakeLists.txt), so the same source gives the same bits
on the machine type the goldens were written on (x86-64: exp over channels from glibc's
libmvec). Elsewhere exp and cos come from another library and differ in the last bits, so
there the floats are compared at rtol 1e-9 (as test_layered_estimator.py's golden values).
"""

import json
import math
import platform

from support.walk_goldens import GOLDENS, digest, generate


def _load():
    with open(GOLDENS) as f:
        return json.load(f)


def _same(a, b, rtol: float = 0.0) -> bool:
    """Equality of nested JSON values: exact for rtol 0 (NaN equals NaN, +0.0 differs from
    -0.0), else floats within rtol."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k], rtol) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(_same(x, y, rtol) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        if math.isnan(a) or math.isnan(b):
            return math.isnan(a) and math.isnan(b)
        if rtol:
            return math.isclose(a, b, rel_tol=rtol, abs_tol=0.0)
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    return type(a) is type(b) and a == b


def test_committed_goldens_are_intact():
    doc = _load()
    assert digest(doc["goldens"]) == doc["sha256"]


def test_walk_reproduces_goldens_bit_for_bit():
    doc = _load()
    want = doc["goldens"]
    got = generate()
    exact = platform.machine() == doc["machine"]
    # Same architecture: a few ulps, not 0. glibc picks its exp/pow/sin variants by CPU
    # features, so two x86_64 hosts can differ in the last bit: the snake case read up to
    # 1.03e-15 relative on an AMD EPYC host (33 of 60 values), every other case 0. Any
    # change to the walk moves values by far more than 4e-15.
    rtol = 4e-15 if exact else 1e-9
    assert got.keys() == want.keys()
    differ = [
        f"{case}/{part}" for case in want for part in want[case] if not _same(got[case][part], want[case][part], rtol)
    ]
    assert not differ, f"outputs changed: {differ}"
