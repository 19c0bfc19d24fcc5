"""/v1/renders: render a named scene (a job) and fetch its image as PNG or EXR."""
from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Path
from fastapi.responses import FileResponse, JSONResponse
from starlette.concurrency import run_in_threadpool

from bsdflab.service import artefact_refs, render_checks, tenancy
from bsdflab.service.bodies import ThreadedBody
from bsdflab.service.deps import ClientDep, JobsDep, SettingsDep, model_spec
from bsdflab.service.errors import ERRORS, NOT_FOUND, over_limit
from bsdflab.service.job_service import JobService
from bsdflab.service.routers.tables import QUEUED
from bsdflab.service.schemas import HASH_PATTERN, RenderInfo, RenderRequest
from bsdflab.service.views import job_info

router = APIRouter(prefix="/v1/renders", tags=["renders"], route_class=ThreadedBody)
Hash = Annotated[str, Path(pattern=HASH_PATTERN, description="the render's content hash (64 hex digits)")]
KIND = "render"


def _links(h: str) -> dict[str, str]:
    return {"self": f"/v1/renders/{h}", "png": f"/v1/renders/{h}/image.png", "exr": f"/v1/renders/{h}/image.exr"}


def render_info(jobs: JobService, h: str, request: dict[str, Any], result: dict[str, Any] | None,
                client) -> RenderInfo:
    job = jobs.visible(jobs.store.latest_for(KIND, h), client)   # never another tenant's job
    live = jobs.job(job["id"]) if job is not None else None
    if result is None and live is None:   # a record whose files are gone, and no job
        raise HTTPException(404, f"no render {h}")
    state = "done" if result is not None else live["state"]
    return RenderInfo(hash=h, state=state, request=artefact_refs.public(request), job=job_info(live) if live else None,
                      summary=None if result is None else result["summary"], links=_links(h))


@router.post("", response_model=RenderInfo, responses={**QUEUED, **ERRORS},
             summary="Render a scene (or get the existing image)")
async def create_render(body: RenderRequest, jobs: JobsDep, settings: SettingsDep, client: ClientDep):
    """200 with the render when this exact request (scene, options, size, spp, seed) was
    rendered before, else 202 with its job; identical requests in flight share it."""
    prepared = await run_in_threadpool(_prepare, body, jobs, settings, client)
    if isinstance(prepared, RenderInfo):
        return prepared
    request, key, stored = prepared
    if stored:   # stored files loaded in a check worker, under its deadline and memory bound; awaited without a thread
        await jobs.checker.run_async("materials", {"materials": stored}, stored[0][0], client.name)
    return await run_in_threadpool(_submit, jobs, request, key, client)


def _prepare(body: RenderRequest, jobs: JobService, settings, client):
    """On a route's thread (not the event loop), bounded by BSDFLAB_LIMIT_STORE_REFS: the
    existing render, or (request, key, the materials that name stored files)."""
    request, key = jobs.prepare(KIND, model_spec(body.model_dump(), jobs, artefact_refs.RENDER_SLOTS, client))
    pixels = request["width"] * request["height"]
    over_limit(settings, "limit_render_pixels", pixels, "width x height")
    over_limit(settings, "limit_render_samples", pixels * request["spp"], "width x height x spp")
    found = jobs.cached(KIND, key) or jobs.adopt(KIND, key, request)
    if found is not None:
        return render_info(jobs, key, request, found, client)
    cells, stored = render_checks.check(request)   # what the worker would refuse, refused now (422)
    over_limit(settings, "limit_table_cells", cells, "options.material's table cells (both lobes counted)")
    if stored:   # the key's queue share before its check takes a check worker's time (429)
        jobs.room(KIND, key, client)
    return request, key, stored


def _submit(jobs: JobService, request: dict[str, Any], key: str, client) -> JSONResponse:
    row, _ = jobs.submit(KIND, request, key, client)
    info = job_info(jobs.job(row["id"]))
    return JSONResponse(info.model_dump(mode="json"), status_code=202, headers={"Location": info.links["self"]})


@router.get("/{key}", response_model=RenderInfo, responses=NOT_FOUND, summary="A render's state and summary")
def get_render(key: Hash, jobs: JobsDep, client: ClientDep) -> RenderInfo:
    row = jobs.store.artefact(key, KIND)
    if row is not None and tenancy.may_read(jobs, row["request"], client):   # another tenant's upload: as absent
        return render_info(jobs, key, row["request"], jobs.cached(KIND, key), client)
    job = jobs.visible(jobs.store.latest_for(KIND, key), client)
    if job is None:
        raise HTTPException(404, f"no render {key}")
    return render_info(jobs, key, job["request"], None, client)


def _file(jobs: JobService, key: str, which: str, client) -> FileResponse:
    row = jobs.store.artefact(key, KIND)
    result = jobs.cached(KIND, key) if row is not None and tenancy.may_read(jobs, row["request"], client) else None
    if result is None:
        raise HTTPException(404, f"no finished render {key}{jobs.job_hint(KIND, key, client)}")
    media = "image/png" if which == "png" else "image/x-exr"
    return FileResponse(jobs.artefact_dir / result["files"][which], media_type=media, filename=f"{key}.{which}")


@router.get("/{key}/image.png", response_class=FileResponse, summary="The image, tone-mapped sRGB PNG",
            responses={**NOT_FOUND, 200: {"content": {"image/png": {}}, "description": "the image"}})
def get_png(key: Hash, jobs: JobsDep, client: ClientDep) -> FileResponse:
    return _file(jobs, key, "png", client)


@router.get("/{key}/image.exr", response_class=FileResponse, summary="The image, linear OpenEXR",
            responses={**NOT_FOUND, 200: {"content": {"image/x-exr": {}}, "description": "the image"}})
def get_exr(key: Hash, jobs: JobsDep, client: ClientDep) -> FileResponse:
    return _file(jobs, key, "exr", client)
