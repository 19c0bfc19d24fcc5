"""Uploads bounded before their bodies are read (ASGI middleware on ``POST /v1/measured`` and
``POST /v1/fits/datasets``).

Per client key: at most ``BSDFLAB_LIMIT_UPLOADS_PER_KEY`` uploads at once, and stored
uploads of at most ``BSDFLAB_LIMIT_UPLOAD_STORAGE_PER_KEY`` bytes (the body's declared size
checked here when already full, and with the upload's own size once its hash is known,
bsdflab.service.uploads); over all clients, at most ``BSDFLAB_LIMIT_UPLOAD_BYTES_IN_FLIGHT`` bytes of
bodies being received (a body without Content-Length counts as the upload cap). Before:
16 concurrent 61 MiB uploads cost +1.6 GB of memory, 48 uploads 2 GB of disk.
"""
from __future__ import annotations

from collections import Counter

from starlette.concurrency import run_in_threadpool

from bsdflab.service.auth import ANONYMOUS
from bsdflab.service.errors import reply
from bsdflab.service.settings import limit_variable

UPLOAD_PATHS = ("/v1/measured", "/v1/fits/datasets")   # measured files and fit data: one set of limits
# A refused upload's body is not read: the connection closes after the answer, so the
# server does not parse (on its event loop) the megabytes the client goes on sending.
CLOSE = {"Connection": "close"}


def quota_message(name: str, stored: int, size: int, quota: int) -> str:
    return (f"client {name!r} stores {stored} bytes of uploads; {size} more would pass its quota of {quota} "
            f"bytes ({limit_variable('limit_upload_storage_per_key')})")


class UploadGate:
    def __init__(self, app, settings, stored_bytes):
        """``stored_bytes(client name)``: bytes of the uploads that client has stored."""
        self.app, self.settings, self.stored_bytes = app, settings, stored_bytes
        self.per_key: Counter[str] = Counter()   # touched from the event loop only
        self.in_flight = 0

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http" or scope["method"] != "POST" or scope["path"].rstrip("/") not in UPLOAD_PATHS:
            return await self.app(scope, receive, send)
        s = self.settings
        name = scope.get("state", {}).get("client", ANONYMOUS).name
        length = dict(scope.get("headers") or []).get(b"content-length", b"")
        # at most the upload cap: a body declared over it is BodyLimit's 413, not a "retry later"
        size = min(int(length), s.limit_measured_bytes) if length.isdigit() else s.limit_measured_bytes
        if self.per_key[name] >= s.limit_uploads_per_key:
            return await reply(send, 429, f"client {name!r} has {self.per_key[name]} uploads in progress, its limit "
                                          f"({limit_variable('limit_uploads_per_key')}); retry later",
                               {"Retry-After": "5", **CLOSE})
        if self.in_flight + size > s.limit_upload_bytes_in_flight:
            return await reply(send, 429, f"{self.in_flight} bytes of uploads are being received; {size} more "
                                          f"would pass {s.limit_upload_bytes_in_flight} "
                                          f"({limit_variable('limit_upload_bytes_in_flight')}); retry later",
                               {"Retry-After": "5", **CLOSE})
        self.per_key[name] += 1
        self.in_flight += size
        try:
            stored = await run_in_threadpool(self.stored_bytes, name)
            if stored >= s.limit_upload_storage_per_key:   # full already: not a byte read
                return await reply(send, 413, quota_message(name, stored, size, s.limit_upload_storage_per_key),
                                   CLOSE)
            return await self.app(scope, receive, send)
        finally:
            self.per_key[name] -= 1
            if not self.per_key[name]:
                del self.per_key[name]
            self.in_flight -= size
