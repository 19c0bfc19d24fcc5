"""The registry of job kinds: a name and the module that implements it.

A kind's module defines three module-level functions:

``normalise(request: dict) -> dict``
    Validate a request (ValueError naming the bad field) and return its canonical form:
    defaults filled in, the model in its ``to_dict`` form. Cheap: no physics runs.
``key(request: dict) -> str``
    The content hash (64 hex digits) of a normalised request: equal requests, equal keys.
    It names the job's artefacts, so a repeated request finds them.
``existing(request: dict, out_dir: Path) -> dict | None``
    The result ``run`` would return when its artefacts are already in ``out_dir`` (made by
    an earlier job, or by another kind: a render's tables), else None.
``run(request, out_dir, progress, cancelled, runner=None) -> dict``
    Do the work: a pure function of the normalised request (its seed included). Calls
    ``progress(fraction)`` now and then, stops with ``JobCancelled`` once ``cancelled()``
    is True, writes its artefacts atomically into ``out_dir`` (named by ``key``) and returns
    a JSON-compatible result. ``runner`` (bsdflab.util.runners) is passed on to the Python
    API; it is given only when the executor has one, so a kind that never splits its work
    may leave it out.

Modules are imported when first used, so that a worker process (or a Dask worker) looks a
kind up by its name alone.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

_MODULES: dict[str, str] = {
    "tabulate": "bsdflab.jobs.tabulate",
    "render": "bsdflab.jobs.render",
}


@dataclass(frozen=True)
class JobKind:
    name: str
    module: ModuleType

    def normalise(self, request: dict) -> dict:
        if not isinstance(request, dict):
            raise ValueError(f"a {self.name} request must be a dict, got {type(request).__name__}")
        return self.module.normalise(request)

    def key(self, request: dict) -> str:
        return self.module.key(request)

    def existing(self, request: dict, out_dir) -> dict | None:
        return self.module.existing(request, Path(out_dir))

    def run(self, request, out_dir, progress, cancelled, runner=None) -> dict:
        extra = {} if runner is None else {"runner": runner}
        return self.module.run(request, out_dir, progress, cancelled, **extra)


def register_kind(name: str, module: str) -> None:
    """Make ``name`` run ``module``'s functions (e.g. ``register_kind("fit", "bsdflab.fit.job")``).
    Executors send the module path along with each job (``module_of``), so a worker
    process or a cluster worker registers it too."""
    if not name or not name.replace("-", "").isalnum():
        raise ValueError(f"a job kind name must be alphanumeric, got {name!r}")
    _MODULES[name] = module


def module_of(name: str) -> str:
    """The module path of kind ``name``."""
    get_kind(name)
    return _MODULES[name]


def kind_names() -> tuple[str, ...]:
    return tuple(_MODULES)


def get_kind(name: str) -> JobKind:
    """The kind called ``name``; ValueError listing the known kinds otherwise."""
    if name not in _MODULES:
        raise ValueError(f"unknown job kind {name!r}; known kinds: {', '.join(_MODULES)}")
    return JobKind(name, importlib.import_module(_MODULES[name]))


def warm_up() -> None:
    """Import every kind's module (seconds of imports a worker process pays once at start
    rather than inside its first job). Not colour-science: renders and tables no longer
    import it (bsdflab/spectra/colour_precomputed.py), and a worker that would only import
    it for a rare figure or fit should not pay 2.4 CPU-s at every start."""
    for name in _MODULES:
        get_kind(name)
