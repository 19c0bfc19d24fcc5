"""/v1/tables: tabulate a model (a job), list tables, read one's metadata, download it."""
from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Path, Query
from fastapi.responses import FileResponse, JSONResponse
from starlette.concurrency import run_in_threadpool

from bsdflab.jobs import tabulate as tabulate_kind
from bsdflab.service import artefact_refs, render_checks, tenancy
from bsdflab.service.bodies import ThreadedBody
from bsdflab.service.deps import ClientDep, JobsDep, SettingsDep, model_spec
from bsdflab.service.errors import ERRORS, NOT_FOUND, over_limit
from bsdflab.service.job_service import JobService
from bsdflab.service.schemas import HASH_PATTERN, JobInfo, TableInfo, TableList, TableRequest
from bsdflab.service.views import job_info

router = APIRouter(prefix="/v1/tables", tags=["tables"], route_class=ThreadedBody)
Hash = Annotated[str, Path(pattern=HASH_PATTERN, description="the table's key (64 hex digits)")]
KIND = "tabulate"
QUEUED = {202: {"model": JobInfo, "description": "tabulation queued (or already running): follow the job"},
          429: {"description": "the job queue is full"}}


def table_info(result: dict[str, Any]) -> TableInfo:
    fields = {name: result[name] for name in TableInfo.model_fields if name not in ("hash", "links")}
    fields["model"] = artefact_refs.public(fields["model"], None)   # a stored file by its hash, never its path
    h = result["hash"]
    return TableInfo(hash=h, links={"self": f"/v1/tables/{h}", "file": f"/v1/tables/{h}/file"}, **fields)


@router.post("", response_model=TableInfo, responses={**QUEUED, **ERRORS},
             summary="Tabulate a model (or get the existing table)")
async def create_table(body: TableRequest, jobs: JobsDep, settings: SettingsDep, client: ClientDep):
    """200 with the table when it exists already (the same model, grid, target error and
    channels: the table cache's key), else 202 with the job that makes it; identical
    requests in flight share it. A model that names stored files (a measured file, a table)
    is built in a check worker (bsdflab.service.offload), once, never in the web process."""
    spec = await run_in_threadpool(_spec, body, jobs, client)
    if render_checks.names_stored(spec.get("model")):
        checked = await jobs.checker.run_async("table", {"request": spec, "out_dir": str(jobs.folder(KIND))},
                                               "model", client.name)
    else:
        checked = None
    return await run_in_threadpool(_create, spec, checked, jobs, settings, client)


def _spec(body: TableRequest, jobs: JobService, client) -> dict[str, Any]:
    """The request with its stored files found (bounded by BSDFLAB_LIMIT_STORE_REFS); when
    one is named, the key's queue share checked before a check worker reads it."""
    spec = model_spec(body.model_dump(exclude_none=True), jobs, client=client)
    if render_checks.names_stored(spec.get("model")):
        jobs.room(KIND, "", client)   # its key is known after the check
    return spec


def _create(spec: dict[str, Any], checked: dict[str, Any] | None, jobs: JobService, settings, client):
    if checked is None:
        request, key = jobs.prepare(KIND, spec)
        cells, existing = tabulate_kind.cells(request), None
    else:   # tabulate.prepared in a check worker
        request, key, cells, existing = checked["request"], checked["key"], checked["cells"], checked["existing"]
    over_limit(settings, "limit_table_cells", cells, "table cells (both lobes counted)")
    if request["wavelengths"] is not None:
        over_limit(settings, "limit_wavelengths", len(request["wavelengths"]), "wavelengths")
    found = jobs.cached(KIND, key)
    if found is None and checked is None:
        found = jobs.adopt(KIND, key, request)
    elif found is None and existing is not None:   # as adopt, from the check worker's look
        jobs.store.put_artefact(key, KIND, request, existing)
        found = existing
    if found is not None:
        return table_info(found)
    row, _ = jobs.submit(KIND, request, key, client)
    info = job_info(jobs.job(row["id"]))
    return JSONResponse(info.model_dump(mode="json"), status_code=202, headers={"Location": info.links["self"]})


@router.get("", response_model=TableList, summary="The tables this server has made")
def list_tables(jobs: JobsDep, client: ClientDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100) -> TableList:
    """Tables made by the client's jobs (an admin: every table), newest first. A table's
    hash is its name: any client that knows it may read the table, unless it was made from
    uploads the client does not hold (bsdflab.service.tenancy)."""
    rows = jobs.store.artefacts(KIND, limit) if client.admin else jobs.store.artefacts_of(KIND, client.name, limit)
    return TableList(tables=[table_info(r["result"]) for r in rows])


def _found(jobs: JobService, key: str, client) -> dict[str, Any]:
    result = jobs.table(key)
    # a table of another tenant's upload is as absent (before: its values by its hash)
    if result is None or not tenancy.may_read(jobs, result.get("model"), client):
        raise HTTPException(404, f"no table {key}{jobs.job_hint(KIND, key, client)}")
    return result


@router.get("/{key}", response_model=TableInfo, responses=NOT_FOUND, summary="A table's metadata")
def get_table(key: Hash, jobs: JobsDep, client: ClientDep) -> TableInfo:
    """Model, grid, lobes, channels, effort (walks per cell) and the achieved relative
    error of the luminance (rms, 95th percentile, max over significant cells)."""
    return table_info(_found(jobs, key, client))


@router.get("/{key}/file", response_class=FileResponse, summary="The table file (OpenEXR)",
            responses={**NOT_FOUND, 200: {"content": {"image/x-exr": {}}, "description": "the table file"}})
def get_table_file(key: Hash, jobs: JobsDep, client: ClientDep) -> FileResponse:
    result = _found(jobs, key, client)
    return FileResponse(jobs.table_dir / result["files"]["exr"], media_type="image/x-exr",
                        filename=f"{key}.exr")
