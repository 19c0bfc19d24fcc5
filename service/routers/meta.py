"""/healthz and /v1/version."""
from __future__ import annotations

import importlib.metadata
import platform

from fastapi import APIRouter

import bsdflab
from bsdflab import _core
from bsdflab.service.deps import KEY, JobsDep, SettingsDep
from bsdflab.service.errors import KEY_ERRORS
from bsdflab.service.schemas import Health, VersionInfo

router = APIRouter(tags=["meta"])


def _mitsuba_version() -> str | None:
    """The installed Mitsuba's version, read from its package metadata (no import)."""
    try:
        return importlib.metadata.version("mitsuba")
    except importlib.metadata.PackageNotFoundError:
        return None


@router.get("/healthz", response_model=Health, summary="Liveness")
async def healthz() -> Health:
    """A coroutine on the event loop: it never waits for a thread, so computation (which
    runs on the heavy pool) cannot delay it."""
    return Health(status="ok")


@router.get("/v1/version", response_model=VersionInfo, dependencies=[KEY], responses=KEY_ERRORS,
            summary="Versions, executor and limits")
def version(settings: SettingsDep, jobs: JobsDep) -> VersionInfo:
    """The package, the C++ core build (module file, threads), Mitsuba's version, the job
    executor and the request limits in force."""
    limits = {name[len("limit_"):]: getattr(settings, name) for name in type(settings).model_fields
              if name.startswith("limit_") and isinstance(getattr(settings, name), int)}
    return VersionInfo(bsdflab=bsdflab.__version__,
                       core={"module": _core.__file__.rsplit("/", 1)[-1], "threads": _core.worker_count()},
                       mitsuba=_mitsuba_version(), python=platform.python_version(),
                       executor=settings.executor, workers=jobs.executor.workers,
                       api_key_required=settings.api_key is not None or bool(settings.api_keys)
                       or settings.api_keys_file is not None, limits=limits)
