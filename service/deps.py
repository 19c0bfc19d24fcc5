"""Dependencies as ``Annotated`` aliases: the settings, the job service, the API key."""
from __future__ import annotations

import hmac
from typing import Annotated

from fastapi import Depends, HTTPException, Request, Security
from fastapi.security import APIKeyHeader, HTTPAuthorizationCredentials, HTTPBearer

from bsdflab.service.job_service import JobService
from bsdflab.service.settings import Settings

_key_header = APIKeyHeader(name="X-API-Key", auto_error=False, description="the service's API key")
_bearer = HTTPBearer(auto_error=False, description="the service's API key as a bearer token")


def get_settings(request: Request) -> Settings:
    return request.app.state.settings


def get_jobs(request: Request) -> JobService:
    return request.app.state.jobs


SettingsDep = Annotated[Settings, Depends(get_settings)]
JobsDep = Annotated[JobService, Depends(get_jobs)]


def require_key(settings: SettingsDep,
                header: Annotated[str | None, Security(_key_header)] = None,
                bearer: Annotated[HTTPAuthorizationCredentials | None, Security(_bearer)] = None) -> None:
    """When an API key is configured, the request must carry it (compared in constant time)."""
    if settings.api_key is None:
        return
    given = header if header is not None else (bearer.credentials if bearer is not None else None)
    expected = settings.api_key.get_secret_value().encode("utf-8")
    if given is None or not hmac.compare_digest(given.encode("utf-8", "surrogateescape"), expected):
        raise HTTPException(401, "a valid API key is required (X-API-Key header or Bearer token)",
                            headers={"WWW-Authenticate": "Bearer"})


KEY = Depends(require_key)
