"""Logging: one format for the service's lines and uvicorn's, a request id on every line
written while a request is served, optionally JSON lines (``BSDFLAB_LOG_FORMAT=json``).

`RequestLog` (ASGI middleware) takes the client's ``X-Request-ID`` when it is a short
token, else makes one, answers it in ``X-Request-ID`` and logs one line per request
(method, path, status, milliseconds). The job service logs each job's lifecycle (queued,
started, done / failed / cancelled, re-queued after restart) under ``bsdflab.service``.
"""
from __future__ import annotations

import contextvars
import json
import logging
import re
import time
import uuid

REQUEST_ID: contextvars.ContextVar[str] = contextvars.ContextVar("bsdflab_request_id", default="-")
TEXT_FORMAT = "%(asctime)s %(levelname)s %(name)s [%(request_id)s] %(message)s"
METHOD_CHARS = 16   # a method name is a client's string too: an 8 KB one is not logged whole
_TOKEN = re.compile(r"[A-Za-z0-9._-]{1,64}")
log = logging.getLogger("bsdflab.service.requests")


class RequestIdFilter(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        record.request_id = REQUEST_ID.get()
        return True


class JsonLines(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        line = {"time": self.formatTime(record), "level": record.levelname, "logger": record.name,
                "request_id": getattr(record, "request_id", "-"), "message": record.getMessage()}
        if record.exc_info:
            line["exception"] = self.formatException(record.exc_info)
        return json.dumps(line)


def log_config(level: str = "info", json_lines: bool = False) -> dict:
    """A ``logging.config.dictConfig`` for the service and uvicorn (uvicorn's access log is
    replaced by `RequestLog`'s lines)."""
    formatter = {"()": JsonLines} if json_lines else {"format": TEXT_FORMAT}
    handler = {"class": "logging.StreamHandler", "formatter": "one", "filters": ["request_id"],
               "stream": "ext://sys.stderr"}
    loggers = {name: {"handlers": ["one"], "level": level.upper(), "propagate": False}
               for name in ("bsdflab", "uvicorn", "uvicorn.error")}
    loggers["uvicorn.access"] = {"handlers": [], "level": "WARNING", "propagate": False}
    return {"version": 1, "disable_existing_loggers": False,
            "filters": {"request_id": {"()": RequestIdFilter}}, "formatters": {"one": formatter},
            "handlers": {"one": handler}, "loggers": loggers}


class RequestLog:
    """Give each request an id (its log lines carry it) and log it when it ends."""

    def __init__(self, app):
        self.app = app

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        given = dict(scope.get("headers") or []).get(b"x-request-id", b"").decode("latin-1")
        request_id = given if _TOKEN.fullmatch(given) else uuid.uuid4().hex[:16]
        token = REQUEST_ID.set(request_id)
        status, start = 0, time.perf_counter()

        async def tagged(message):
            nonlocal status
            if message["type"] == "http.response.start":
                status = message["status"]
                message = {**message, "headers": [*message.get("headers", []),
                                                  (b"x-request-id", request_id.encode())]}
            await send(message)

        try:
            await self.app(scope, receive, tagged)
        finally:
            # the path as a JSON string: a client's %0A cannot forge a log line
            # a method is a token (the HTTP parser refuses spaces and controls); cut to 16 characters
            log.info("%s %s %d %.1f ms", scope["method"][:METHOD_CHARS], json.dumps(scope["path"][:256]), status,
                     1000 * (time.perf_counter() - start))
            REQUEST_ID.reset(token)
