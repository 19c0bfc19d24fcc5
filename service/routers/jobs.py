"""/v1/jobs: a job's state and progress, its cancellation, and progress as server-sent
events (so a page follows a job without polling)."""
from __future__ import annotations

import asyncio
from collections.abc import AsyncIterable
from typing import Annotated, Any

from fastapi import APIRouter, Depends, HTTPException, Path, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.sse import EventSourceResponse, ServerSentEvent

from bsdflab.jobs import FINISHED
from bsdflab.service.deps import ClientDep, JobsDep, SettingsDep
from bsdflab.service.errors import NOT_FOUND
from bsdflab.service.schemas import JOB_ID_PATTERN, JobInfo, JobList
from bsdflab.service.settings import limit_variable
from bsdflab.service.views import job_info

router = APIRouter(prefix="/v1/jobs", tags=["jobs"], responses=NOT_FOUND)
JobId = Annotated[str, Path(pattern=JOB_ID_PATTERN, description="a job id (32 hex digits)")]


def existing_job(job_id: JobId, jobs: JobsDep, client: ClientDep) -> dict[str, Any]:
    row = jobs.visible(jobs.job(job_id), client)
    if row is None:
        raise HTTPException(404, f"no job {job_id}")
    return row


JobRow = Annotated[dict, Depends(existing_job)]


@router.get("", response_model=JobList, summary="Recent jobs")
def list_jobs(jobs: JobsDep, client: ClientDep,
              state: Annotated[str | None, Query(pattern="^(queued|running|done|failed|cancelled)$")] = None,
              limit: Annotated[int, Query(ge=1, le=1000)] = 100) -> JobList:
    """The client's own jobs (those it created or joined), newest first; an admin key sees
    every client's."""
    rows = jobs.store.jobs(limit, state, client=None if client.admin else client.name)
    return JobList(jobs=[job_info(r) for r in rows])


@router.get("/{job_id}", response_model=JobInfo, summary="A job's state and progress")
def get_job(row: JobRow) -> JobInfo:
    """State (queued, running, done, failed, cancelled), progress fraction, elapsed seconds
    and the estimated seconds left."""
    return job_info(row)


@router.delete("/{job_id}", response_model=JobInfo, responses={409: {"description": "the job has already finished"}},
               summary="Cancel a job")
def cancel_job(row: JobRow, jobs: JobsDep, client: ClientDep) -> JobInfo:
    """Cancel a queued or running job: it stops within a moment and its state becomes
    cancelled (``cancel_requested`` is true until then). Finished jobs answer 409. Only the
    client that created the job (or an admin) may cancel it; one that joined it gets 403."""
    if not client.admin and row.get("owner") != client.name:
        raise HTTPException(403, f"job {row['id']} was started by another client; only it or an admin may cancel it")
    if row["state"] == "cancelled":
        return job_info(row)
    if row["state"] in FINISHED or not jobs.cancel(row["id"]):
        raise HTTPException(409, f"job {row['id']} has already finished ({row['state']})")
    return job_info(jobs.job(row["id"]))


async def stream_slot(request: Request, client: ClientDep, settings: SettingsDep):
    """One of the client's ``BSDFLAB_LIMIT_EVENT_STREAMS_PER_KEY`` progress streams, held
    until the stream ends (a stream outlives every connection timeout: 300 of them on one
    job held /v1/jobs up for seconds, and the connection cap is reached at 512)."""
    streams = request.app.state.event_streams   # touched from the event loop only
    if streams[client.name] >= settings.limit_event_streams_per_key:
        raise HTTPException(429, f"client {client.name!r} has {streams[client.name]} progress streams open, its "
                                 f"limit ({limit_variable('limit_event_streams_per_key')}); close one or poll "
                                 "GET /v1/jobs/{id}", headers={"Retry-After": "5"})
    streams[client.name] += 1
    try:
        yield
    finally:   # after the stream's last event, or its client's leaving
        streams[client.name] -= 1
        if not streams[client.name]:
            del streams[client.name]


@router.get("/{job_id}/events", response_class=EventSourceResponse, summary="Progress as server-sent events")
async def job_events(row: JobRow, jobs: JobsDep, settings: SettingsDep,
                     _: Annotated[None, Depends(stream_slot)]) -> AsyncIterable[ServerSentEvent]:
    """A ``progress`` event (the job, as GET /v1/jobs/{id} returns it) whenever its state or
    progress changes, then one ``done``, ``failed`` or ``cancelled`` event, and the stream
    ends."""
    job_id, last = row["id"], None
    while True:
        current = await run_in_threadpool(jobs.job, job_id)
        info = job_info(current)
        if info.state in FINISHED:
            yield ServerSentEvent(data=info, event=info.state, id=job_id)
            return
        seen = (info.state, round(info.progress, 3), info.cancel_requested)
        if seen != last:
            last = seen
            yield ServerSentEvent(data=info, event="progress", id=job_id)
        await asyncio.sleep(settings.progress_interval_s)
