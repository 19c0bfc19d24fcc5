"""The FastAPI application: ``create_app(settings)``; ``bsdflab serve`` runs it with uvicorn."""
from __future__ import annotations

import contextlib
import gc
from collections import Counter

from fastapi import FastAPI
from fastapi.staticfiles import StaticFiles
from starlette.concurrency import run_in_threadpool

import bsdflab
from bsdflab.jobs import register_kind
from bsdflab.service import auth, errors, logs, metrics
from bsdflab.service.deps import KEY
from bsdflab.service.errors import KEY_ERRORS
from bsdflab.service.heavy import HeavyPool
from bsdflab.service.job_service import JobService
from bsdflab.service.routers import (
    bsdf,
    catalog,
    docs,
    fits,
    jobs,
    measured,
    meta,
    page,
    renders,
    tables,
    thinfilm,
    validations,
)
from bsdflab.service.settings import Settings
from bsdflab.service.upload_gate import UPLOAD_PATHS, UploadGate
from bsdflab.util import native_output

DESCRIPTION = """BSDF queries, thin-film spectra, tables and renders from bsdflab's Python API.

Models are given in their `to_dict` form or as a preset name with keyword overrides.
Tabulations and renders are jobs: `POST` answers 202 with the job (follow it at
`/v1/jobs/{id}` or as server-sent events at `/v1/jobs/{id}/events`) or 200 when the result
exists already. Artefacts are content-addressed: the same request finds the same files.
Every request a client can send gets a 2xx or a 4xx with a message."""


def _warm_up() -> None:
    """colour-science's import and the sRGB weights, before the first request: the first
    spectral evaluation paid them (about a second of the GIL on a heavy thread, while
    /healthz waited: the bench's profile, docs/service.md "Performance")."""
    from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights

    srgb_weights(DEFAULT_WAVELENGTHS)


def create_app(settings: Settings | None = None) -> FastAPI:
    settings = settings or Settings()

    clients = auth.load_clients(settings)

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI):
        # threads serve requests: no process-wide descriptor swapping (it lost the logs)
        capturing = native_output.capture_descriptors(False)
        app.state.jobs = JobService(settings)
        await run_in_threadpool(_warm_up)
        # The objects alive now (the imports': about 200 000) are never garbage; frozen, the
        # cyclic collector no longer walks them: each full collection held the GIL, and the
        # event loop with it, for 120-160 ms (the loaded 2-core machine), /healthz's p99.
        gc.collect()
        gc.freeze()
        try:
            yield
        finally:
            app.state.jobs.close()
            app.state.heavy.close()
            native_output.capture_descriptors(capturing)

    app = FastAPI(title="bsdflab", version=bsdflab.__version__, description=DESCRIPTION, lifespan=lifespan,
                  docs_url=None, redoc_url=None)   # served by routers.docs, without a CDN
    app.state.settings = settings
    bsdf.MODELS.max_bytes = settings.model_cache_bytes
    app.state.heavy = HeavyPool(settings.heavy_concurrency, settings.compute_deadline_s)
    app.state.event_streams = Counter()   # open progress streams by client (routers.jobs)
    app.state.metrics = metrics.Metrics()
    app.state.metrics.bind(app)
    errors.install(app)
    app.add_middleware(errors.BodyLimit, limit=settings.limit_body_bytes,
                       routes={path: ("limit_measured_bytes", settings.limit_measured_bytes)
                               for path in UPLOAD_PATHS})
    app.add_middleware(UploadGate, settings=settings,                       # after the key, before the body
                       stored_bytes=lambda client: app.state.jobs.store.upload_bytes(client))
    app.add_middleware(errors.HeadAsGet)
    app.add_middleware(auth.KeyCheck, clients=clients, reply=errors.reply)   # before any body is read
    app.add_middleware(metrics.Timing, metrics=app.state.metrics)
    app.add_middleware(logs.RequestLog)                                      # outermost: every request logged
    app.include_router(meta.router)
    app.include_router(metrics.router)
    app.include_router(page.router)
    app.include_router(docs.router)
    register_kind("validate", "bsdflab.validation.job")   # a layer above bsdflab.jobs: registered by name
    register_kind("fit", "bsdflab.fit.job")
    for module in (catalog, bsdf, thinfilm, tables, measured, renders, validations, fits, jobs):
        app.include_router(module.router, dependencies=[KEY], responses=KEY_ERRORS)
    app.mount("/static", StaticFiles(directory=page.STATIC_DIR), name="static")
    if not clients:
        app.openapi = lambda: _without_security(app)
    return app


def _without_security(app: FastAPI) -> dict:
    """The OpenAPI schema with the API-key requirements taken out: without a configured key
    no endpoint asks for one, and the schema should say so."""
    if app.openapi_schema is None:
        schema = FastAPI.openapi(app)
        for path in schema.get("paths", {}).values():
            for operation in path.values():
                operation.pop("security", None)
                operation.get("responses", {}).pop("401", None)
        schema.get("components", {}).pop("securitySchemes", None)
        app.openapi_schema = schema
    return app.openapi_schema
