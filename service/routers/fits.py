"""/v1/fits: a fitting study (bsdflab.fit, as ``bsdflab fit``) as a job, its data files uploaded
by hash (``POST /v1/fits/datasets``) and the study folder's files as artefacts by name.
Cancel with ``DELETE /v1/jobs/{id}``; the queue limits and shares of every job apply."""
from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Path, Query, Request
from fastapi.responses import FileResponse, JSONResponse
from starlette.concurrency import run_in_threadpool

from bsdflab.fit import job as fit_job
from bsdflab.fit.gonio_instrument import TERMS as GONIO_TERMS
from bsdflab.fit.sampling import MAP_ITERATIONS
from bsdflab.fit.stack_forward import BANDWIDTH_NODES, CONE_AZIMUTHS, CONE_NODES
from bsdflab.service import fit_uploads, uploads
from bsdflab.service.bodies import ThreadedBody
from bsdflab.service.deps import ClientDep, JobsDep, SettingsDep
from bsdflab.service.errors import ERRORS, NOT_FOUND, over_limit
from bsdflab.service.job_service import JobService
from bsdflab.service.routers.tables import QUEUED
from bsdflab.service.schemas import HASH_PATTERN, FitDataInfo, FitDataList, FitInfo, FitRequest
from bsdflab.service.views import job_info

router = APIRouter(prefix="/v1/fits", tags=["fits"], route_class=ThreadedBody)
Hash = Annotated[str, Path(pattern=HASH_PATTERN, description="the fit's content hash (64 hex digits)")]
FileName = Annotated[str, Path(pattern=r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$", description="a file of the study")]
KIND = "fit"
DATASETS = "/v1/fits/datasets"
BODY = {"requestBody": {"required": True, "content": {"application/octet-stream": {
    "schema": {"type": "string", "format": "binary"}}}}}
MEDIA = {".json": "application/json", ".png": "image/png", ".csv": "text/csv", ".md": "text/markdown",
         ".nc": "application/x-netcdf"}


def _links(h: str, names: list[str] | None) -> dict[str, str]:
    links = {"self": f"/v1/fits/{h}"}
    for name in names or ():
        links[name] = f"/v1/fits/{h}/files/{name}"
    return links


def _info(jobs: JobService, h: str, request: dict[str, Any], result: dict[str, Any] | None, client) -> FitInfo:
    job = jobs.visible(jobs.store.latest_for(KIND, h), client)   # never another tenant's job
    live = jobs.job(job["id"]) if job is not None else None
    if result is None and live is None:
        raise HTTPException(404, f"no fit {h}")
    names = None if result is None else sorted(result["files"])
    return FitInfo(hash=h, state="done" if result is not None else live["state"], request=request,
                   job=job_info(live) if live else None, summary=None if result is None else result["summary"],
                   files=names, links=_links(h, names))


# Over HTTP one adding-doubling solve of the full model is bounded by these (the CLI takes
# the config's full ranges, nodes 256 and orders 4096): the limit counts solves, not their cost.
HTTP_MAX_NODES, HTTP_MAX_ORDERS = 64, 512
# the instrument quadrature a structure fit's step costs, relative to the defaults
QUADRATURE_DEFAULT = BANDWIDTH_NODES * CONE_NODES * CONE_AZIMUTHS


def map_evaluations(s, n_free: int) -> int:
    """Forward evaluations of the MAP stage (bsdflab.fit.sampling.find_map): its pool of
    prior draws, then map_starts L-BFGS-B runs of up to MAP_ITERATIONS iterations of a
    central-difference gradient (2 n + 1 evaluations each)."""
    return max(256, 32 * s.map_starts) + s.map_starts * MAP_ITERATIONS * (2 * n_free + 1)


def _structure_checks(config, raw: dict[str, Any]) -> float:
    """A structure config's own refusals over HTTP; returns the weight of one walker step
    (the instrument quadrature's size against the defaults), for the smooth and the full
    model alike (the full model's gonio rows take the same slit and cone settings)."""
    if "appearance" in raw:
        raise HTTPException(422, "[appearance]: a structure study makes no appearance draws or renders; "
                                 "remove the table")
    free = len(config.priors) + sum(len(spec.instrument.priors) for spec in config.datasets)
    if config.sampler.kind == "emcee" and config.sampler.walkers < 2 * free:
        raise HTTPException(422, f"[sampler] walkers must be at least twice the number of free parameters "
                                 f"({2 * free}, more with scale_per_series), got {config.sampler.walkers}")
    m = config.model
    if getattr(m, "kind", None) == "full":
        if m.nodes > HTTP_MAX_NODES or m.orders > HTTP_MAX_ORDERS:
            raise HTTPException(422, f"[model] nodes at most {HTTP_MAX_NODES} and orders at most "
                                     f"{HTTP_MAX_ORDERS} over HTTP (one solve's cost is not counted), "
                                     f"got {m.nodes} and {m.orders}")
    return max(1.0, m.bandwidth_nodes * m.cone_nodes * m.cone_azimuths / QUADRATURE_DEFAULT)


def check_limits(settings, request: dict[str, Any]) -> None:
    """422 naming the limit when the fit's work passes one (as a render's pixels)."""
    config = fit_job.config_of(request)
    over_limit(settings, "limit_fit_files", len(request["data"]), "the number of data files")
    structure = fit_job.is_structure(request)
    weight = _structure_checks(config, request["config"]) if structure else 1.0
    s = config.sampler
    n_free = len(config.priors) if structure else len(config.free)
    if s.kind == "emcee":
        # the MAP stage's evaluations count as walker steps (before: uncounted, up to
        # 1000 starts x 500 iterations), and a structure's instrument quadrature weighs each
        over_limit(settings, "limit_fit_walker_steps", int(weight * (s.walkers * s.max_steps
                                                                       + map_evaluations(s, n_free))),
                   "[sampler] walkers x max_steps + the MAP stage's evaluations, x the instrument "
                   "quadrature ([model] bandwidth_nodes x cone_nodes x cone_azimuths) over its default")
    else:
        over_limit(settings, "limit_fit_live_points", s.live_points, "[sampler] live_points")
    m = config.model
    if getattr(m, "kind", None) == "full":
        # emulator_nodes = 0 solves the model at every likelihood evaluation (before: uncounted,
        # 2^21 direct solves passed); the emulator's error checks are direct solves too.
        # A structure's emulator spans its free structure parameters and each dataset's free
        # offset, cone and slit (bsdflab.fit.full_stack_posterior); every solve is weighed by
        # the instrument quadrature, as a walker step is
        free = ([n for n in config.priors if n != "noise_scale"]
                + [t for spec in config.datasets for t in spec.instrument.priors if t in GONIO_TERMS]
                if structure else config.free)
        if m.emulator_nodes and (free or not structure):
            solves, what = m.emulator_nodes ** len(free), "[model] emulator_nodes ^ free parameters"
        elif s.kind == "emcee":
            why = "no free structure parameter" if m.emulator_nodes else "emulator_nodes = 0"
            solves = s.walkers * s.max_steps + map_evaluations(s, n_free)
            what = f"[model] {why}: walkers x max_steps + the MAP stage's direct solves"
        elif m.emulator_nodes:   # a structure with no free structure parameter: no emulator to bound
            raise HTTPException(422, "[model] no free structure parameter with the nested sampler: its direct solves "
                                     "have no bound; use [sampler] kind = 'emcee' (BSDFLAB_LIMIT_FIT_EMULATOR_SOLVES)")
        else:
            raise HTTPException(422, "[model] emulator_nodes = 0 with the nested sampler: its direct solves have "
                                     "no bound; give emulator_nodes (BSDFLAB_LIMIT_FIT_EMULATOR_SOLVES)")
        over_limit(settings, "limit_fit_emulator_solves", int(weight * (solves + m.emulator_checks)),
                   f"{what} + emulator_checks, x the instrument quadrature over its default")
    if structure:   # a structure's study has no appearance draws or renders (bsdflab.fit.stack_study)
        return
    ap = config.appearance
    # each posterior draw is evaluated at every angle (before: angles_deg had no length bound)
    over_limit(settings, "limit_fit_walker_steps", ap.draws * len(ap.angles_deg), "[appearance] draws x angles_deg")
    over_limit(settings, "limit_render_samples", ap.renders * ap.render_size ** 2 * ap.render_spp,
               "[appearance] renders x render_size^2 x render_spp")
    over_limit(settings, "limit_render_pixels", (ap.renders + 1) * ap.render_size ** 2,
               "[appearance] (renders + 1) x render_size^2")


@router.post("/datasets", response_model=FitDataInfo, responses=ERRORS, openapi_extra=BODY,
             summary="Upload a data file for fits (long CSV, wide CSV, .ProcSpec, ...)")
async def upload_dataset(request: Request, jobs: JobsDep, client: ClientDep, settings: SettingsDep,
                         name: Annotated[str, Query(min_length=1, max_length=128, description=(
                             "the file's name (its suffix tells the format: .csv, .ProcSpec, ...)"))]
                         ) -> FitDataInfo:
    """The raw file as the body (``application/octet-stream``, at most
    ``BSDFLAB_LIMIT_MEASURED_BYTES``), read by bsdflab.fit's readers (422 naming the file,
    line and column) and stored under its SHA-256. The per-key upload limits and storage
    quota of measured files apply to both together."""
    data = await request.body()
    result = await fit_uploads.upload(jobs, data, name, client.name, settings.limit_upload_storage_per_key)
    return FitDataInfo(hash=result["hash"], format=result["format"], summary=result["summary"])


@router.get("/datasets", response_model=FitDataList, summary="The fit data files this client uploaded")
def list_datasets(jobs: JobsDep, client: ClientDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100
                  ) -> FitDataList:
    rows = jobs.store.uploads_of(fit_uploads.KIND, None if client.admin else client.name, limit)
    return FitDataList(datasets=[FitDataInfo(hash=r["result"]["hash"], format=r["result"]["format"],
                                             summary=r["result"]["summary"]) for r in rows])


@router.post("", response_model=FitInfo, responses={**QUEUED, **ERRORS},
             summary="Fit a model to uploaded data (or get the existing study)")
async def create_fit(body: FitRequest, jobs: JobsDep, settings: SettingsDep, client: ClientDep):
    """The config is checked first (422 naming the TOML section and key), then the limits,
    then the data (422 naming the upload, file, line and column); 202 with the job, or 200
    with the study when this exact request ran before."""
    prepared = await run_in_threadpool(_prepare, body, jobs, settings, client)
    if isinstance(prepared, FitInfo):
        return prepared
    request, key = prepared
    # one read of uploaded files per client at once, as its uploads (before: as many reads at
    # once as the route's threads, each up to BSDFLAB_LIMIT_MEASURED_BYTES, before any 429)
    lock = uploads.client_lock(client.name)
    if not lock.acquire(blocking=False):
        raise HTTPException(429, f"client {client.name!r} has an upload or a fit's data being read; retry later",
                            headers={"Retry-After": "2"})
    try:   # what the worker would refuse, refused now (422): read in a check worker, awaited without a thread
        await jobs.checker.run_async("dataset", {"request": request, "out_dir": str(jobs.artefact_dir)},
                                     "the fit's data", client.name)
    finally:
        lock.release()
    return await run_in_threadpool(_submit, jobs, request, key, client)


def _prepare(body: FitRequest, jobs: JobService, settings, client):
    """On a route's thread: the existing study, or (request, key) with its uploads found,
    its limits and the key's queue share checked (before its data takes a check worker)."""
    request, key = jobs.prepare(KIND, body.model_dump())
    check_limits(settings, request)
    for i, item in enumerate(request["data"]):
        # only the client's own uploads (an admin: any): another tenant's file is as absent
        # (before: any stored hash, and the study's data.csv handed its rows back). Checked
        # before the cache: the same request by another tenant got the finished study.
        if not fit_uploads.stored(jobs, item["hash"]) or not _may_read(jobs, [item], client):
            raise HTTPException(422, f"data[{i}].hash: no uploaded fit data file {item['hash']} "
                                     f"(upload it with POST {DATASETS})")
    found = jobs.cached(KIND, key) or jobs.adopt(KIND, key, request)
    if found is not None:
        return _info(jobs, key, request, found, client)
    # read here, before the queue's admission: one upload named 64 times was 64 copies and reads
    total = sum(fit_uploads.size(jobs, item["hash"]) for item in request["data"])
    over_limit(settings, "limit_measured_bytes", total, "the bytes of the fit's data files together")
    jobs.room(KIND, key, client)
    return request, key


def _may_read(jobs: JobService, data: list[dict[str, Any]], client) -> bool:
    """A study hands its data back (data.csv, the residuals, the posterior it implies): only a
    client that uploaded every one of its files, or an admin, may see it or its files."""
    return client.admin or all(jobs.store.uploaded(item["hash"], client.name) for item in data)


def _submit(jobs: JobService, request: dict[str, Any], key: str, client) -> JSONResponse:
    row, _ = jobs.submit(KIND, request, key, client)
    info = job_info(jobs.job(row["id"]))
    return JSONResponse(info.model_dump(mode="json"), status_code=202, headers={"Location": info.links["self"]})


@router.get("/{key}", response_model=FitInfo, responses=NOT_FOUND, summary="A fit's state, summary and files")
def get_fit(key: Hash, jobs: JobsDep, client: ClientDep) -> FitInfo:
    row = jobs.store.artefact(key, KIND)
    if row is not None and _may_read(jobs, row["request"]["data"], client):
        return _info(jobs, key, row["request"], jobs.cached(KIND, key), client)
    job = jobs.visible(jobs.store.latest_for(KIND, key), client)
    if job is None:
        raise HTTPException(404, f"no fit {key}")
    return _info(jobs, key, job["request"], None, client)


@router.get("/{key}/files/{name}", response_class=FileResponse, responses=NOT_FOUND,
            summary="A file of the study folder (summary.json, material.json, corner.png, ...)")
def get_file(key: Hash, name: FileName, jobs: JobsDep, client: ClientDep) -> FileResponse:
    """Only the names the study wrote (``files`` of ``GET /v1/fits/{hash}``) are served."""
    row = jobs.store.artefact(key, KIND)
    result = jobs.cached(KIND, key) if row is not None and _may_read(jobs, row["request"]["data"], client) else None
    if result is None:
        raise HTTPException(404, f"no finished fit {key}{jobs.job_hint(KIND, key, client)}")
    relative = result["files"].get(name)
    if relative is None:
        raise HTTPException(404, f"fit {key} has no file {name!r}; its files: {', '.join(sorted(result['files']))}")
    suffix = name[name.rfind("."):] if "." in name else ""
    return FileResponse(jobs.artefact_dir / relative, media_type=MEDIA.get(suffix, "application/octet-stream"),
                        filename=name)
