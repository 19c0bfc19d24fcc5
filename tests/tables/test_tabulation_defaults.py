"""The tabulator's defaults are written once, in core/include/bsdflab/tabulation.h (they
were 64 pilot walks in C++ and 512 in Python): every Python entry point reads the core's."""

from __future__ import annotations

import inspect

from bsdflab import _core
from bsdflab.tables import stages, tabulate
from bsdflab.tables.request import TableRequest


def test_python_defaults_are_the_cores():
    core = _core.TabulationSettings
    # 512 pilot walks: the effort docs/coverage.md measured the error coverage at
    assert (core.default_min_samples, core.default_max_samples, core.default_floor) == (512, 65536, 0.05)
    assert (stages.DEFAULT_MIN_SAMPLES, stages.DEFAULT_MAX_SAMPLES, stages.ERROR_FLOOR) == (
        core.default_min_samples,
        core.default_max_samples,
        core.default_floor,
    )
    for f in (tabulate, stages.pilot_cells, TableRequest.make):
        p = inspect.signature(f).parameters
        assert p["min_samples"].default == core.default_min_samples, f
