"""Client errors as 4xx: the Python API's ValueError (and its TypeError / OverflowError on
values pydantic let through) become 422 with the message; a full queue is 429; a body over
the size limit is 413 (uvicorn has no limit of its own, so an ASGI middleware counts)."""
from __future__ import annotations

import json

from fastapi import FastAPI, HTTPException, Request
from fastapi.responses import JSONResponse

from bsdflab.service.schemas import Error
from bsdflab.service.settings import limit_variable
from bsdflab.service.store import QueueFull

CLIENT_ERRORS = (ValueError, TypeError, OverflowError)
# Documented on every route that takes a body or parameters (FastAPI adds 422's schema).
ERRORS = {400: {"description": "malformed request"},
          413: {"description": "request body over the size limit"},
          422: {"model": Error, "description": "invalid request: the field, the valid range or the limit"}}
KEY_ERRORS = {401: {"description": "missing or wrong API key"}}
NOT_FOUND = {404: {"description": "no such job, table or render"}}


def over_limit(settings, field: str, value: int, what: str) -> None:
    """422 naming the limit when ``value`` exceeds setting ``field``."""
    limit = getattr(settings, field)
    if value > limit:
        raise HTTPException(422, f"{what} is {value}, more than the limit of {limit} "
                                 f"({limit_variable(field)})")


def install(app: FastAPI) -> None:
    async def client_error(request: Request, exc: Exception) -> JSONResponse:
        return JSONResponse({"detail": str(exc) or type(exc).__name__}, status_code=422)

    async def queue_full(request: Request, exc: QueueFull) -> JSONResponse:
        return JSONResponse({"detail": f"{exc} ({limit_variable('limit_queue')}); retry later"},
                            status_code=429, headers={"Retry-After": "5"})

    for cls in CLIENT_ERRORS:
        app.add_exception_handler(cls, client_error)
    app.add_exception_handler(QueueFull, queue_full)


class _TooLarge(Exception):
    pass


class BodyLimit:
    """Refuse request bodies over ``limit`` bytes with 413, by Content-Length when given and
    by counting the streamed body otherwise."""

    def __init__(self, app, limit: int):
        self.app, self.limit = app, limit

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        length = dict(scope.get("headers") or []).get(b"content-length")
        if length is not None:
            try:
                declared = int(length)
            except ValueError:
                return await _reply(send, 400, "Content-Length is not an integer")
            if declared > self.limit:
                return await _reply(send, 413, self._message(declared))
        received, started = 0, False

        async def counted():
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.limit:
                    raise _TooLarge
            return message

        async def tracked(message):
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, counted, tracked)
        except _TooLarge:
            if not started:
                await _reply(send, 413, self._message(received))

    def _message(self, size: int) -> str:
        return (f"request body of {size} bytes is over the limit of {self.limit} bytes "
                f"({limit_variable('limit_body_bytes')})")


async def _reply(send, status: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})
