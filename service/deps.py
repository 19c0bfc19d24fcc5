"""Dependencies as ``Annotated`` aliases: the settings, the job service, the heavy pool, the
client (identified by `bsdflab.service.auth.KeyCheck` before the route runs)."""
from __future__ import annotations

from typing import Annotated, Any

from fastapi import Depends, Request, Security
from fastapi.security import APIKeyHeader, HTTPAuthorizationCredentials, HTTPBearer

from bsdflab.service import artefact_refs, tenancy
from bsdflab.service.auth import ANONYMOUS, Client
from bsdflab.service.heavy import HeavyPool
from bsdflab.service.job_service import JobService
from bsdflab.service.settings import Settings

_key_header = APIKeyHeader(name="X-API-Key", auto_error=False, description="a client's API key")
_bearer = HTTPBearer(auto_error=False, description="a client's API key as a bearer token")


def get_settings(request: Request) -> Settings:
    return request.app.state.settings


def get_jobs(request: Request) -> JobService:
    return request.app.state.jobs


def get_heavy(request: Request) -> HeavyPool:
    return request.app.state.heavy


SettingsDep = Annotated[Settings, Depends(get_settings)]
JobsDep = Annotated[JobService, Depends(get_jobs)]
HeavyDep = Annotated[HeavyPool, Depends(get_heavy)]


def require_key(request: Request,
                header: Annotated[str | None, Security(_key_header)] = None,
                bearer: Annotated[HTTPAuthorizationCredentials | None, Security(_bearer)] = None) -> Client:
    """The client the middleware identified (the key itself was checked there, before the
    body was read; the parameters only document the scheme in the OpenAPI schema)."""
    return request.scope.get("state", {}).get("client", ANONYMOUS)


KEY = Depends(require_key)
ClientDep = Annotated[Client, Depends(require_key)]


def model_spec(spec: dict[str, Any], jobs: JobService, slots=artefact_refs.MODEL_SLOTS,
               client: Client | None = None) -> dict[str, Any]:
    """A request's model spec with tables and measured files named by hash checked in the
    store; any server path refused (bsdflab.service.artefact_refs). ``slots``: where the
    request holds a model (a render: its ``options.material``). A measured file is found
    only among ``client``'s own uploads (an admin's: any): another tenant's is as absent
    (before: any stored hash, so its values could be evaluated by whoever computed it); so
    is a table made from another tenant's upload (bsdflab.service.tenancy; before: named by
    its hash, it evaluated and rendered the upload's values)."""
    stored_file = jobs.stored_file
    if client is not None and not client.admin:
        def stored_file(model_type: str, content_hash: str):
            if model_type != "table" and not jobs.store.uploaded(content_hash, client.name):
                return None
            if model_type == "table" and not tenancy.may_read(jobs, {"type": "table", "hash": content_hash}, client):
                return None
            return jobs.stored_file(model_type, content_hash)
    return artefact_refs.resolve(spec, stored_file, jobs.settings.limit_store_refs, slots)


def client_of(request: Request) -> Client:
    """The client of a request (as ``require_key``), for work run off the route's own thread."""
    return request.scope.get("state", {}).get("client", ANONYMOUS)
