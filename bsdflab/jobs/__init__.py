"""bsdflab.jobs: the one job abstraction under the CLI, the HTTP service and a cluster.

The seam (kept stable; the service and ``bsdflab.distributed`` are written against it)
------------------------------------------------------------------------------------------
Job kinds
    A kind is a module with module-level pure functions (``bsdflab.jobs.kinds`` documents
    them), registered by name: ``"tabulate"`` (bsdflab.jobs.tabulate) and ``"render"``
    (bsdflab.jobs.render); ``register_kind(name, module)`` adds more ("validate", "fit").
    The work itself is::

        run(request: dict, out_dir: Path, progress: Callable[[float], None],
            cancelled: Callable[[], bool], runner=None) -> dict

    ``request`` is the kind's normalised request dict (``normalise``), ``out_dir`` the
    content-addressed folder its artefacts go to, written atomically and named by
    ``key(request)``; ``progress`` takes the fraction done in [0, 1]; the job raises
    ``JobCancelled`` soon after ``cancelled()`` turns True; ``runner`` (a
    ``bsdflab.util.runners.Runner``) is handed on to the Python API (``tabulate(..., runner=)``,
    ``render(..., runner=)``), and given only when the executor has one. The result is plain
    JSON.

Executors (``bsdflab.jobs.executor``)
    ``JobExecutor`` (abstract): ``submit(kind, request, out_dir) -> JobHandle`` and
    ``shutdown()``. ``JobHandle``: ``progress() -> (fraction, elapsed_s, eta_s | None)``,
    ``cancel()``, ``done()``, ``result(timeout=None)`` (raises ``JobFailed`` or
    ``JobCancelled``), ``state`` (queued, running, done, failed, cancelled). Executors
    drive a handle through ``_started()``, ``_progress(f)`` and ``_finish(result, error)``;
    ``execute(kind, request, out_dir, progress, cancelled, runner)`` runs one job and turns
    its outcome into a tuple that crosses process boundaries (``outcome_error``).
    ``make_executor(spec, workers)`` (``bsdflab.jobs.factory``), spec from the
    ``BSDFLAB_EXECUTOR`` setting: ``"processes"`` (default; `ProcessJobExecutor`),
    ``"threads"`` (`ThreadJobExecutor`), or ``"<runner>:<target>"`` (`RunnerJobExecutor`:
    drivers on threads here, units on a runner registered by name in
    ``bsdflab.util.runners``, e.g. ``"dask:<scheduler address>"`` / ``"dask:local:N"``,
    which ``bsdflab.distributed`` registers; a clear RuntimeError if it cannot be imported).

Progress and cancel from inside the Python API
    ``bsdflab.util.progress.monitored(progress, cancelled)`` makes every C++ job started in its
    block report ``progress(stage, fraction)`` and stop on ``cancelled()``; kinds wrap
    their API call in it. Work done elsewhere (a cluster) reports with
    ``bsdflab.util.progress.report_progress`` and polls ``bsdflab.util.progress.cancel_requested``.

Dedup and caching
    ``key(request)`` is the content hash. For tables it is the table cache's own key
    (``bsdflab.tables.cache_key``), so a table asked for twice, or by a render, is one file.
"""
from bsdflab.jobs.executor import FINISHED, STATES, JobExecutor, JobFailed, JobHandle, execute, outcome_error
from bsdflab.jobs.factory import default_workers, make_executor
from bsdflab.jobs.kinds import JobKind, get_kind, kind_names, module_of, register_kind
from bsdflab.util.progress import JobCancelled

__all__ = ["FINISHED", "STATES", "JobCancelled", "JobExecutor", "JobFailed", "JobHandle", "JobKind",
           "default_workers", "execute", "get_kind", "kind_names", "make_executor", "module_of", "outcome_error",
           "register_kind"]
