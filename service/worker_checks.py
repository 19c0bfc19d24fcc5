"""The job kind ``check``: what reads a client's file, run in a check worker process
(bsdflab.service.offload), never in the web process.

A request is ``{"check": name, "args": {...}, "memory_bytes": n}``; ``run`` answers the
check's summary (JSON) or raises ValueError with the message a client gets. Checks:

``measured``  an uploaded RGL ``.bsdf`` or MERL ``.binary`` read by its reader
              (bsdflab.service.uploads): its summary.
``fitdata``   an uploaded fit data file read by the fit's readers
              (bsdflab.service.fit_uploads): its summary.
``dataset``   a fit request's data files read together with its sidecar, as its job
              reads them (bsdflab.service.fit_uploads): how many files.
``table``     a table request whose model names stored files, normalised with the model
              built once (bsdflab.jobs.tabulate.prepared): the request, its key, cells
              and the table when it exists.
``materials`` a render's materials that name stored files, built with the files loaded
              (bsdflab.service.render_checks): what the render job would refuse.

The worker's address space may grow by at most ``memory_bytes`` during a check
(``RLIMIT_AS``, set before and restored after) over its size after its first check's imports
(measured once: a reused worker's grown heap does not widen it; ``malloc_trim`` after each
check hands freed memory back): a file that needs more is a MemoryError, not the machine's memory.
"""
from __future__ import annotations

import contextlib
import ctypes
import importlib
import resource
from typing import Any

KIND = "check"


def normalise(request: dict[str, Any]) -> dict[str, Any]:
    if request.get("check") not in CHECKS or not isinstance(request.get("args"), dict):
        raise ValueError(f"a check request names one of {', '.join(CHECKS)} and its args")
    return request


def key(request: dict[str, Any]) -> str:   # checks are not stored: no artefact to name
    return ""


def existing(request: dict[str, Any], out_dir) -> None:
    return None


_baseline: int | None = None   # this worker's address space once every check's module is imported


def run(request: dict[str, Any], out_dir, progress, cancelled) -> dict[str, Any]:
    global _baseline
    if _baseline is None:   # every check's imports before the baseline: not a file's cost
        for module, _ in CHECKS.values():
            importlib.import_module(module)
        _baseline = _address_space()
    module, name = CHECKS[request["check"]]
    check = getattr(importlib.import_module(module), name)
    try:
        with memory_bound(request.get("memory_bytes"), _baseline):
            return check(**request["args"])
    finally:
        _trim()


@contextlib.contextmanager
def memory_bound(budget: int | None, baseline: int | None = None):
    """At most ``budget`` bytes of address space inside the block over ``baseline`` (the
    worker's size when it started, so that what earlier checks left mapped in a reused
    worker does not widen the bound; None: its size now, and no bound when ``budget`` is None)."""
    if budget is None:
        yield
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = (_address_space() if baseline is None else baseline) + int(budget)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _trim() -> None:
    """Hand the heap's free memory back to the system after a check (glibc's malloc_trim;
    elsewhere nothing): a reused worker keeps less of a large file's memory mapped."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def _address_space() -> int:
    """This process's virtual size in bytes (VmSize)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    return 0


CHECKS = {"measured": ("bsdflab.service.uploads", "read_summary"),
          "fitdata": ("bsdflab.service.fit_uploads", "read_summary"),
          "materials": ("bsdflab.service.render_checks", "check_materials"),
          "dataset": ("bsdflab.service.fit_uploads", "read_dataset"),
          "table": ("bsdflab.jobs.tabulate", "prepared")}
