"""Client errors as 4xx: the Python API's ValueError (and its TypeError / OverflowError on
values pydantic let through) become 422 with the message (at most MAX_MESSAGE_CHARS of it);
a full queue is 429; a body over the size limit is 413 (uvicorn has no limit of its own, so
an ASGI middleware counts); a 405 names every method of the path in ``Allow``, and HEAD
answers wherever GET does."""
from __future__ import annotations

import json

from fastapi import FastAPI, HTTPException, Request
from fastapi.encoders import jsonable_encoder
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import Match

from bsdflab.service.schemas import Error
from bsdflab.service.settings import limit_variable
from bsdflab.service.store import QueueFull

CLIENT_ERRORS = (ValueError, TypeError, OverflowError)
MAX_ERRORS = 20          # validation errors in one 422; the rest are counted, not listed
MAX_INPUT_CHARS = 200    # of an invalid input echoed in one
MAX_MESSAGE_CHARS = 1000  # of a Python API error's message (it may quote the input: an unknown name of 1 MB)
METHODS = ("GET", "POST", "PUT", "PATCH", "DELETE")
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
        return JSONResponse({"detail": cut_message(str(exc) or type(exc).__name__)}, status_code=422)

    async def queue_full(request: Request, exc: QueueFull) -> JSONResponse:
        return JSONResponse({"detail": f"{exc} ({limit_variable(exc.setting)}); retry later"},
                            status_code=429, headers={"Retry-After": "5"})

    async def http_error(request: Request, exc: StarletteHTTPException) -> Response:
        if exc.status_code == 405:   # Starlette names only the first matching route's methods
            return JSONResponse({"detail": exc.detail}, status_code=405,
                                headers={"Allow": ", ".join(allowed_methods(request.app, request.scope))})
        return await http_exception_handler(request, exc)

    async def invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse({"detail": bounded_errors(exc.errors())}, status_code=422)

    for cls in CLIENT_ERRORS:
        app.add_exception_handler(cls, client_error)
    app.add_exception_handler(RequestValidationError, invalid)
    app.add_exception_handler(QueueFull, queue_full)
    app.add_exception_handler(StarletteHTTPException, http_error)


def cut_message(text: str) -> str:
    """A message as answered: its start when longer than MAX_MESSAGE_CHARS."""
    return text if len(text) <= MAX_MESSAGE_CHARS else text[:MAX_MESSAGE_CHARS] + "..."


def _short(value):
    """An invalid input as echoed in a 422: itself when short, else its start as text (a
    large list is cut before it is encoded, not after)."""
    if isinstance(value, (list, tuple, dict)) and len(value) > 16:
        items = list(value.items() if isinstance(value, dict) else value)[:16]
        value = dict(items) if isinstance(value, dict) else items
        cut = True
    else:
        cut = False
    text = json.dumps(jsonable_encoder(value), default=str)
    if cut or len(text) > MAX_INPUT_CHARS:
        return text[:MAX_INPUT_CHARS] + "..."
    return value


def bounded_errors(errors) -> list[dict]:
    """At most MAX_ERRORS entries: the first validation errors, each echoed input cut to
    MAX_INPUT_CHARS, and (when there are more) a last entry counting the rest, so a 422's
    size does not grow with the body's."""
    shown, kept = [], len(errors) if len(errors) <= MAX_ERRORS else MAX_ERRORS - 1
    for error in list(errors[:kept]):
        error = {k: v for k, v in error.items() if k != "url"}
        if "input" in error:
            error["input"] = _short(error["input"])
        if "ctx" in error:
            error["ctx"] = {k: str(v)[:MAX_INPUT_CHARS] for k, v in error["ctx"].items()}
        shown.append(jsonable_encoder(error))
    if len(errors) > kept:
        shown.append({"type": "more_errors", "loc": [], "msg": f"and {len(errors) - kept} more errors "
                                                               "(only the first are listed)"})
    return shown


class BodyLimit:
    """Refuse request bodies over ``limit`` bytes with 413: by Content-Length when given;
    a body without one (chunked) is read here, up to the limit, before the route sees it
    (so a chunked body over the limit is a 413 too, not a parse error). ``routes`` gives
    paths their own cap, ``{path: (settings field, bytes)}`` (an upload's)."""

    def __init__(self, app, limit: int, routes: dict[str, tuple[str, int]] | None = None):
        self.app, self.routes = app, {"": ("limit_body_bytes", limit), **(routes or {})}

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        field, limit = self.routes.get(scope["path"].rstrip("/"), self.routes[""])
        length = dict(scope.get("headers") or []).get(b"content-length")
        if length is not None:
            try:
                declared = int(length)
            except ValueError:
                return await reply(send, 400, "Content-Length is not an integer")
            if declared > limit:   # the body is not read: close rather than drain it
                return await reply(send, 413, _too_large(declared, field, limit), {"Connection": "close"})
            return await self.app(scope, receive, send)   # the server holds the body to its length
        chunks, received = [], 0
        while True:
            message = await receive()
            if message["type"] != "http.request":   # the client left
                return
            chunks.append(message.get("body", b""))
            received += len(chunks[-1])
            if received > limit:
                return await reply(send, 413, _too_large(received, field, limit, streamed=True),
                                   {"Connection": "close"})
            if not message.get("more_body", False):
                break
        replayed = False

        async def replay():
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": b"".join(chunks), "more_body": False}
            return await receive()   # then the disconnect, when it comes

        await self.app(scope, replay, send)


def _too_large(size: int, field: str, limit: int, streamed: bool = False) -> str:
    return (f"request body of {'more than ' if streamed else ''}{size} bytes is over the limit of "
            f"{limit} bytes ({limit_variable(field)})")


class HeadAsGet:
    """HEAD on any GET route: the GET's status and headers, without the body."""

    def __init__(self, app):
        self.app = app

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http" or scope["method"] != "HEAD":
            return await self.app(scope, receive, send)

        async def headers_only(message):
            if message["type"] == "http.response.body":
                if not message.get("more_body", False):
                    await send({"type": "http.response.body", "body": b"", "more_body": False})
                return
            await send(message)

        await self.app({**scope, "method": "GET"}, receive, headers_only)


def allowed_methods(app, scope) -> list[str]:
    """Every method some route answers at the request's path (HEAD wherever GET is)."""
    methods = {m for m in METHODS if any(route.matches({**scope, "method": m})[0] == Match.FULL
                                          for route in app.router.routes)}
    if "GET" in methods:
        methods.add("HEAD")
    return sorted(methods)


async def reply(send, status: int, detail: str, headers: dict[str, str] | None = None) -> None:
    """A JSON error answered straight from a middleware (before any route runs)."""
    body = json.dumps({"detail": detail}).encode()
    extra = [(k.lower().encode(), v.encode()) for k, v in (headers or {}).items()]
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
                            *extra]})
    await send({"type": "http.response.body", "body": body})
