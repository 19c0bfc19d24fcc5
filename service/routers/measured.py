"""/v1/measured: upload a measured BSDF file (RGL ``.bsdf`` or MERL), list a client's own.

Uploaded files are named by their SHA-256 in models (bsdflab.service.uploads); no route
takes or answers a server path."""
from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request

from bsdflab.service import uploads
from bsdflab.service.deps import ClientDep, JobsDep, SettingsDep
from bsdflab.service.errors import ERRORS
from bsdflab.service.schemas import MeasuredInfo, MeasuredList

router = APIRouter(prefix="/v1/measured", tags=["measured"])
BODY = {"requestBody": {"required": True, "content": {"application/octet-stream": {
    "schema": {"type": "string", "format": "binary"}}}}}


def info(result: dict) -> MeasuredInfo:
    return MeasuredInfo(hash=result["hash"], format=result["format"], summary=result["summary"])


@router.post("", response_model=MeasuredInfo, responses=ERRORS, openapi_extra=BODY,
             summary="Upload a measured BSDF file (RGL .bsdf or MERL .binary)")
async def upload_measured(request: Request, jobs: JobsDep, client: ClientDep, settings: SettingsDep,
                          format: Annotated[Literal["rgl", "merl"], Query(description="the file's format")]
                          ) -> MeasuredInfo:
    """The raw file as the body (``application/octet-stream``, at most
    ``BSDFLAB_LIMIT_MEASURED_BYTES``), checked by bsdflab's reader (422 with its message,
    naming the field) and stored under its SHA-256; the same bytes answer the same hash.
    Per key: ``BSDFLAB_LIMIT_UPLOADS_PER_KEY`` at once and ``BSDFLAB_LIMIT_UPLOAD_STORAGE_PER_KEY``
    bytes stored (413 beyond); 429 while ``BSDFLAB_LIMIT_UPLOAD_BYTES_IN_FLIGHT`` is taken."""
    data = await request.body()
    result = await uploads.upload(jobs, data, format, client.name, settings.limit_upload_storage_per_key)
    return info(result)


@router.get("", response_model=MeasuredList, summary="The measured files this client uploaded")
def list_measured(jobs: JobsDep, client: ClientDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100
                  ) -> MeasuredList:
    """The client's own uploads (an admin: every upload), newest first. A hash is a
    capability: any client that knows it may use the file in a model."""
    rows = jobs.store.uploads_of(uploads.KIND, None if client.admin else client.name, limit)
    return MeasuredList(measured=[info(r["result"]) for r in rows])
