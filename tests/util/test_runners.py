"""Runners (bsdflab.util.runners): the work-unit path gives the in-process results bit for
bit without a cluster, reports progress and stops on cancel; the registry finds runners by
name, the Dask one through its lazy entry."""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.render import render
from bsdflab.render.units import render_units
from bsdflab.scenes import scene
from bsdflab.tables import TableGrid, tabulate
from bsdflab.util.progress import JobCancelled, monitored
from bsdflab.util.runners import RUNNERS, LocalRunner, Runner, get_runner, open_runner, resolve


def test_tabulate_on_the_local_runner_equals_tabulate_bit_for_bit():
    model, grid = bl.presets.xenopeltis(), TableGrid(3, 4, 3, (360.0,))
    kw = dict(rel_error=0.05, min_samples=32, max_samples=128, seed=7, progress=False)
    local = tabulate(model, grid, **kw)
    units = tabulate(model, grid, runner=LocalRunner(), **kw)
    assert units.meta["units"] >= 2 and units.meta["workers"] == 1
    for name in ("values", "stderr", "samples"):
        assert np.array_equal(getattr(local, name), getattr(units, name)), name


def test_render_on_the_local_runner_equals_render_bit_for_bit():
    s = scene("basic-materials", width=24, height=18)
    local = render(s, spp=4, seed=3, pass_spp=2, progress=False)
    units = render_units(LocalRunner(), s, spp=4, seed=3, pass_spp=2, strategy=0, progress=False,
                         unit_samples=24 * 2 * 5)
    assert units.settings["units"] == 4 * 2  # 4 bands x 2 passes
    assert np.array_equal(local.mean, units.mean) and np.array_equal(local.variance, units.variance)
    assert local.invalid_samples == units.invalid_samples
    assert render(s, spp=4, seed=3, pass_spp=2, progress=False, runner=LocalRunner()).settings["units"] >= 1


def test_local_runner_reports_progress_and_stops_on_cancel():
    seen: list[tuple[str, float]] = []
    with monitored(lambda stage, f: seen.append((stage, f)), lambda: False):
        LocalRunner().run(lambda x, u: x + u, [10], [1, 2, 3, 4], lambda u, v: None, key="k", desc="d",
                          progress=False)
    assert seen == [("d", 0.25), ("d", 0.5), ("d", 0.75), ("d", 1.0)]
    ran: list[int] = []
    with pytest.raises(JobCancelled):
        LocalRunner().run(lambda u: ran.append(u), [], [1, 2, 3], lambda u, v: None, key="k",
                          progress=False, cancelled=lambda: len(ran) == 2)
    assert ran == [1, 2]


def test_registry_and_resolve():
    assert get_runner("local") is LocalRunner
    assert {"dask", "local"} <= set(RUNNERS.names())
    assert issubclass(get_runner("dask"), Runner)  # the lazy entry imports bsdflab.distributed
    with pytest.raises(ValueError, match="unknown runner 'nope'; known: dask, local"):
        get_runner("nope")
    with pytest.raises(ValueError, match="runner or client, not both"):
        resolve(LocalRunner(), client=object())
    with pytest.raises(ValueError, match="runner must be a bsdflab.util.runners.Runner"):
        resolve("local")
    assert resolve() is None
    with open_runner("local") as r:
        assert isinstance(r, LocalRunner)


def test_a_subclass_without_its_own_name_does_not_replace_its_parent():
    class Tweaked(LocalRunner):
        def workers(self) -> int:
            return 2

    assert get_runner("local") is LocalRunner
