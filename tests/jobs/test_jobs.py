"""bsdflab.jobs: job kinds equal the Python API, executors report progress, cancel, and
survive failing jobs and dying workers."""
from __future__ import annotations

import importlib.util
import os

import numpy as np
import pytest

from bsdflab import presets
from bsdflab.jobs import JobCancelled, JobFailed, get_kind, make_executor, register_kind
from bsdflab.jobs import tabulate as tabulate_kind
from bsdflab.jobs.processes import ProcessJobExecutor
from bsdflab.jobs.threads import ThreadJobExecutor
from bsdflab.tables import TableGrid, cache_key, read_table, tabulate
from support.liveness import HANG_S, wait_until

register_kind("test-steps", "support.job_kinds")
SMALL = {"preset": "xenopeltis-thin-film", "grid": {"n_theta_i": 2, "n_theta_o": 3, "n_phi": 3},
         "rel_error": 0.2, "min_samples": 64, "max_samples": 64, "seed": 7, "method": "pfmc"}


def wait_for(predicate):
    wait_until(predicate, "state the test waits for")


def test_tabulate_kind_equals_the_python_api(tmp_path):
    """Same request -> the same table as tabulate() (walks are seeded per cell), under the
    table cache's own key."""
    kind = get_kind("tabulate")
    request = kind.normalise(SMALL)
    seen = []
    result = kind.run(request, tmp_path, seen.append, lambda: False)
    model = presets.xenopeltis_thin_film()
    grid = TableGrid(2, 3, 3)
    # The key holds every setting that changes the table: effort and seed too.
    assert result["hash"] == kind.key(request) == cache_key(model.to_dict(), grid, 0.2, ("R", "G", "B"), 64,
                                                            max_samples=64, seed=7)
    assert kind.key(request) != kind.key({**request, "seed": 8})
    direct = tabulate(model, grid, rel_error=0.2, min_samples=64, max_samples=64, seed=7, progress=False)
    stored = read_table(tmp_path / result["files"]["exr"])
    np.testing.assert_array_equal(stored.values, direct.values)
    np.testing.assert_array_equal(stored.samples, direct.samples)
    assert kind.existing(request, tmp_path)["hash"] == result["hash"]


def test_a_transmissive_model_gives_a_two_sided_table(tmp_path):
    """A table job of a transmissive stack (smooth top, smooth base: adding-doubling, the
    automatic method) writes a two-sided table (format version 3, four parts) and says so."""
    stack = {"type": "layered", "interfaces": [{"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}],
             "slabs": [{"thickness_um": 2.0, "sigma_a": 0.1, "sigma_s": 2.0}],
             "base": {"type": "dielectric", "int_ior": 1.33, "ext_ior": 1.5}}
    kind = get_kind("tabulate")
    request = kind.normalise({"model": stack, "grid": {"n_theta_i": 2, "n_theta_o": 3, "n_phi": 3},
                              "rel_error": 0.05})
    assert request["method"] == "adding-doubling"
    result = kind.run(request, tmp_path, [].append, lambda: False)
    table = read_table(tmp_path / result["files"]["exr"])
    assert table.two_sided and table.values.shape[0] == 4
    assert result["lobes"] == list(table.lobes) == ["reflection", "transmission", "reflection_below",
                                                    "transmission_below"]


def test_requests_are_normalised_and_bad_ones_named():
    kind = get_kind("tabulate")
    a = kind.normalise(SMALL)
    b = kind.normalise({**SMALL, "preset": None, "model": presets.xenopeltis_thin_film().to_dict()})
    assert a == b and kind.key(a) == kind.key(b)
    with pytest.raises(ValueError, match="rel_error"):
        kind.normalise({**SMALL, "rel_error": 0})
    with pytest.raises(ValueError, match="unknown table request fields: colour"):
        kind.normalise({**SMALL, "colour": 1})
    with pytest.raises(ValueError, match="unknown scene"):
        get_kind("render").normalise({"scene": "nowhere"})
    assert tabulate_kind.cells(a) == 4 * 2 * 3 * 3  # four parts: a two-sided table's, the upper bound
    # "auto" (the default): adding-doubling where it covers the model, said in the request
    auto = kind.normalise({k: v for k, v in SMALL.items() if k != "method"})
    assert auto["method"] == "adding-doubling" and auto["method_note"].startswith("automatic")
    assert kind.key(auto) != kind.key(a)
    diffuse = kind.normalise({"model": {"type": "diffuse", "reflectance": 0.5}})
    assert diffuse["method"] == "pfmc" and "Layered" in diffuse["method_note"]


def test_thread_executor_progress_and_cancel(tmp_path):
    with ThreadJobExecutor(1) as executor:
        handle = executor.submit("tabulate", get_kind("tabulate").normalise(SMALL), tmp_path)
        assert handle.result(timeout=120)["hash"]
        assert handle.progress()[0] == 1.0 and handle.state == "done"
        # a long tabulation (many cells) stops within moments of cancel: the core checks
        # between cells
        long = get_kind("tabulate").normalise({**SMALL, "grid": {"n_theta_i": 8, "n_theta_o": 16, "n_phi": 9},
                                               "min_samples": 256, "max_samples": 256})
        running = executor.submit("tabulate", long, tmp_path)
        queued = executor.submit("test-steps", {"steps": 5}, tmp_path)
        wait_for(lambda: running.state == "running")
        assert queued.cancel() and queued.state == "cancelled"   # never started
        running.cancel()
        with pytest.raises(JobCancelled):
            running.result(timeout=HANG_S)
    assert not (tmp_path / f"{get_kind('tabulate').key(long)}.exr").exists()


@pytest.fixture(scope="module")
def processes():
    executor = ProcessJobExecutor(1, cancel_grace_s=2.0)
    yield executor
    executor.shutdown()


def test_process_executor_runs_jobs_in_a_worker(processes, tmp_path):
    handle = processes.submit("test-steps", {"steps": 20, "step_s": 0.05}, tmp_path)
    wait_for(lambda: handle.progress()[0] > 0.2)
    fraction, elapsed, eta = handle.progress()
    assert handle.state == "running" and elapsed > 0 and eta is not None and eta > 0
    result = handle.result(timeout=HANG_S)
    assert result["pid"] != os.getpid() and result["pid"] in processes.worker_pids()


def test_process_executor_cancel_failure_and_crash(processes, tmp_path):
    slow = processes.submit("test-steps", {"steps": 10_000, "step_s": 0.01}, tmp_path)
    wait_for(lambda: slow.state == "running")
    slow.cancel()
    with pytest.raises(JobCancelled):
        slow.result(timeout=HANG_S)
    with pytest.raises(JobFailed, match="asked to fail") as failed:
        processes.submit("test-steps", {"action": "fail"}, tmp_path).result(timeout=HANG_S)
    assert failed.value.error_type == "ValueError"
    with pytest.raises(JobFailed, match="worker process died") as died:
        processes.submit("test-steps", {"action": "crash"}, tmp_path).result(timeout=HANG_S)
    assert died.value.error_type == "WorkerDied"
    # a new worker takes the next job
    assert processes.submit("test-steps", {"steps": 1}, tmp_path).result(timeout=HANG_S)["pid"] != os.getpid()


def test_make_executor_specs():
    with pytest.raises(ValueError, match="unknown executor"):
        make_executor("cluster", 1)
    with pytest.raises(ValueError, match="workers"):
        make_executor("threads", 0)
    make_executor("threads", 2).shutdown()
    if importlib.util.find_spec("bsdflab.distributed") is None:
        with pytest.raises(RuntimeError, match="bsdflab.distributed"):
            make_executor("dask:local:1", 1)
