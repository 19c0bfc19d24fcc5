"""The adding-doubling solver reproduces its goldens bit for bit (tests/support/solver_goldens.py
lists the stacks: every path of the solve). A refactor of core/src/adding_doubling*.cpp must
not change a single bit; a change that means to must regenerate the goldens and say why."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.support import solver_goldens

GOLDENS = json.loads(solver_goldens.PATH.read_text())


def test_01_goldens_cover_every_case():
    assert sorted(GOLDENS) == sorted(solver_goldens.CASES)


@pytest.mark.parametrize("name", list(solver_goldens.CASES))
def test_02_bit_identical(name):
    got, want = solver_goldens.outputs(name), GOLDENS[name]
    assert sorted(got) == sorted(want)
    for key in want:
        a, b = np.asarray(got[key], dtype=np.float64), np.asarray(want[key], dtype=np.float64)
        assert a.shape == b.shape, key
        differ = a.view(np.uint64) != b.view(np.uint64)
        assert not np.any(differ), (
            f"{name} {key}: {np.count_nonzero(differ)} of {a.size} values differ in their bits, "
            f"largest relative change {np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)):.3g}"
        )
