"""/v1/validations: the validation report (bsdflab.validation, as ``bsdflab validate``) as a
job, its HTML and JSON report as artefacts by hash. Cancel with ``DELETE /v1/jobs/{id}``;
the queue limits and shares of every job apply."""
from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Path
from fastapi.responses import FileResponse, JSONResponse

from bsdflab.service.bodies import ThreadedBody
from bsdflab.service.deps import ClientDep, JobsDep, SettingsDep
from bsdflab.service.errors import ERRORS, NOT_FOUND
from bsdflab.service.job_service import JobService
from bsdflab.service.routers.tables import QUEUED
from bsdflab.service.schemas import HASH_PATTERN, ValidationFamily, ValidationInfo, ValidationRequest
from bsdflab.service.settings import limit_variable
from bsdflab.service.views import job_info
from bsdflab.validation.job import benchmark_level
from bsdflab.validation.registry import LEVELS, REGISTRY
from bsdflab.validation.report import load_checks

router = APIRouter(prefix="/v1/validations", tags=["validations"], route_class=ThreadedBody)
Hash = Annotated[str, Path(pattern=HASH_PATTERN, description="the report's content hash (64 hex digits)")]
KIND = "validate"


def _links(h: str) -> dict[str, str]:
    return {"self": f"/v1/validations/{h}", "html": f"/v1/validations/{h}/report.html",
            "json": f"/v1/validations/{h}/results.json"}


def _info(jobs: JobService, h: str, request: dict[str, Any], result: dict[str, Any] | None,
          client) -> ValidationInfo:
    job = jobs.visible(jobs.store.latest_for(KIND, h), client)
    live = jobs.job(job["id"]) if job is not None else None
    if result is None and live is None:
        raise HTTPException(404, f"no validation report {h}")
    return ValidationInfo(hash=h, state="done" if result is not None else live["state"], request=request,
                          job=job_info(live) if live else None,
                          summary=None if result is None else result["summary"],
                          exit_status=None if result is None else result["exit_status"], links=_links(h))


@router.post("", response_model=ValidationInfo, responses={**QUEUED, **ERRORS},
             summary="Run the validation checks (or get the existing report)")
def create_validation(body: ValidationRequest, jobs: JobsDep, settings: SettingsDep, client: ClientDep):
    """The checks of ``bsdflab validate`` at ``level`` (those of ``families`` whose name
    matches ``only``) as a job: 202 with the job, or 200 with the report when this request ran before."""
    if LEVELS.index(body.level) > LEVELS.index(settings.limit_validation_level):
        raise HTTPException(422, f"level {body.level!r} is above this server's limit of "
                                 f"{settings.limit_validation_level!r} ({limit_variable('limit_validation_level')})")
    benchmarks = benchmark_level(body.model_dump())
    if benchmarks is not None and LEVELS.index(benchmarks) > LEVELS.index(settings.limit_validation_level):
        # a quick report's benchmarks are standard's (minutes): not below a quick cap
        raise HTTPException(422, f"benchmarks run at level {benchmarks!r}, above this server's limit of "
                                 f"{settings.limit_validation_level!r} ({limit_variable('limit_validation_level')})")
    request, key = jobs.prepare(KIND, body.model_dump())
    found = jobs.cached(KIND, key) or jobs.adopt(KIND, key, request)
    if found is not None:
        return _info(jobs, key, request, found, client)
    row, _ = jobs.submit(KIND, request, key, client)
    info = job_info(jobs.job(row["id"]))
    return JSONResponse(info.model_dump(mode="json"), status_code=202, headers={"Location": info.links["self"]})


@router.get("/families", response_model=list[ValidationFamily], summary="The check families a request may name")
def list_families() -> list[ValidationFamily]:
    """Every family of checks (``families`` of POST /v1/validations), with its number of checks."""
    load_checks()
    return [ValidationFamily(name=f, checks=n) for f, n in REGISTRY.families().items()]


@router.get("/{key}", response_model=ValidationInfo, responses=NOT_FOUND, summary="A report's state and summary")
def get_validation(key: Hash, jobs: JobsDep, client: ClientDep) -> ValidationInfo:
    row = jobs.store.artefact(key, KIND)
    if row is not None:
        return _info(jobs, key, row["request"], jobs.cached(KIND, key), client)
    job = jobs.visible(jobs.store.latest_for(KIND, key), client)
    if job is None:
        raise HTTPException(404, f"no validation report {key}")
    return _info(jobs, key, job["request"], None, client)


def _file(jobs: JobService, key: str, which: str, media: str, client) -> FileResponse:
    result = jobs.cached(KIND, key)
    if result is None:
        raise HTTPException(404, f"no finished validation report {key}{jobs.job_hint(KIND, key, client)}")
    return FileResponse(jobs.artefact_dir / result["files"][which], media_type=media)


@router.get("/{key}/report.html", response_class=FileResponse, summary="The report (self-contained HTML)",
            responses={**NOT_FOUND, 200: {"content": {"text/html": {}}, "description": "the report"}})
def get_html(key: Hash, jobs: JobsDep, client: ClientDep) -> FileResponse:
    return _file(jobs, key, "html", "text/html", client)


@router.get("/{key}/results.json", response_class=FileResponse, summary="The results document (JSON)",
            responses={**NOT_FOUND, 200: {"content": {"application/json": {}}, "description": "the results"}})
def get_json(key: Hash, jobs: JobsDep, client: ClientDep) -> FileResponse:
    return _file(jobs, key, "json", "application/json", client)
