"""The job kind ``check``: what reads a client's file, run in a check worker process
(bsdflab.service.offload), never in the web process.

A request is ``{"check": name, "args": {...}, "memory_bytes": n}``; ``run`` answers the
check's summary (JSON) or raises ValueError with the message a client gets. Checks:

``measured``  an uploaded RGL ``.bsdf`` or MERL ``.binary`` read by its reader
              (bsdflab.service.uploads): its summary.
``fitdata``   an uploaded fit data file read by the fit's readers
              (bsdflab.service.fit_uploads): its summary.
``materials`` a render's materials that name stored files, built with the files loaded
              (bsdflab.service.render_checks): what the render job would refuse.

The worker's address space may grow by at most ``memory_bytes`` during a check
(``RLIMIT_AS``, set before and restored after): a file that needs more is a MemoryError,
not the machine's memory.
"""
from __future__ import annotations

import contextlib
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


def run(request: dict[str, Any], out_dir, progress, cancelled) -> dict[str, Any]:
    module, name = CHECKS[request["check"]]
    check = getattr(importlib.import_module(module), name)   # imported before the bound: not the file's cost
    with memory_bound(request.get("memory_bytes")):
        return check(**request["args"])


@contextlib.contextmanager
def memory_bound(budget: int | None):
    """At most ``budget`` more bytes of address space inside the block (None: no bound)."""
    if budget is None:
        yield
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = _address_space() + int(budget)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _address_space() -> int:
    """This process's virtual size in bytes (VmSize)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    return 0


CHECKS = {"measured": ("bsdflab.service.uploads", "read_summary"),
          "fitdata": ("bsdflab.service.fit_uploads", "read_summary"),
          "materials": ("bsdflab.service.render_checks", "check_materials")}
