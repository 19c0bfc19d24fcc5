"""uvicorn's h11 protocol with the timeouts and the connection cap the service needs.

uvicorn times out an idle keep-alive connection only after a first response: a socket that
connects and sends nothing, or sends its headers or body a byte at a time, stays open for
ever, and with ``limit_concurrency`` such sockets make every request, ``/healthz``
included, a 503 (40 idle sockets did it). `bounded_protocol(settings)` is the h11 protocol
with:

- a header deadline: a connection that has not sent a complete request line and headers
  ``BSDFLAB_SERVER_HEADER_TIMEOUT_S`` after it opened (or after its last response) is
  closed, however slowly it trickles bytes;
- a read timeout: a request whose body stalls for ``BSDFLAB_SERVER_READ_TIMEOUT_S`` is
  closed (a request being computed or streamed, server-sent events, is not);
- a body deadline: a request whose body is not complete ``BSDFLAB_SERVER_BODY_TIMEOUT_S``
  after its headers is closed (a byte every few seconds never stalls, and held an upload's
  share of ``BSDFLAB_LIMIT_UPLOAD_BYTES_IN_FLIGHT`` for ever);
- the connection cap (``BSDFLAB_SERVER_LIMIT_CONCURRENCY``) applied per request rather than
  by uvicorn: beyond it every path answers 503 except ``/healthz``, which still answers.
"""
from __future__ import annotations

from uvicorn.protocols.http.flow_control import service_unavailable
from uvicorn.protocols.http.h11_impl import H11Protocol

HEALTH = "/healthz"


def bounded_protocol(settings) -> type[H11Protocol]:
    """The protocol class for ``uvicorn.Config(http=...)`` (with ``limit_concurrency=None``:
    the cap is this class's)."""
    return type("BoundedH11Protocol", (_Bounded,), {
        "header_timeout_s": settings.server_header_timeout_s, "read_timeout_s": settings.server_read_timeout_s,
        "body_timeout_s": settings.server_body_timeout_s,
        "cap": settings.server_limit_concurrency})


class _Bounded(H11Protocol):
    header_timeout_s: float = 10.0
    read_timeout_s: float = 30.0
    body_timeout_s: float = 600.0
    cap: int = 512

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.app = self._capped(self.app)
        self._timer = None
        self._waiting_since = self._last_data = self._cycle_since = 0.0
        self._timed_cycle = None

    def _capped(self, app):
        async def gate(scope, receive, send):
            if scope["type"] == "http" and scope["path"] != HEALTH and (
                    len(self.connections) >= self.cap or len(self.tasks) > self.cap):
                return await service_unavailable(scope, receive, send)
            return await app(scope, receive, send)
        return gate

    # -- the timers ------------------------------------------------------------------------
    def connection_made(self, transport) -> None:
        super().connection_made(transport)
        self._waiting_since = self._last_data = self.loop.time()
        self._arm()

    def data_received(self, data: bytes) -> None:
        self._last_data = self.loop.time()
        super().data_received(data)
        if self.cycle is not self._timed_cycle:   # its headers arrived just now
            self._timed_cycle, self._cycle_since = self.cycle, self._last_data

    def on_response_complete(self) -> None:
        self._waiting_since = self.loop.time()
        super().on_response_complete()

    def connection_lost(self, exc) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        super().connection_lost(exc)

    def _arm(self) -> None:
        tick = max(0.05, min(self.header_timeout_s, self.read_timeout_s, self.body_timeout_s) / 4)
        self._timer = self.loop.call_later(tick, self._check)

    def _check(self) -> None:
        self._timer = None
        if self.transport.is_closing():
            return
        now = self.loop.time()
        between_requests = self.cycle is None or self.cycle.response_complete
        if between_requests and now - self._waiting_since >= self.header_timeout_s:
            return self._close()
        if not between_requests and self.cycle.more_body and (now - self._last_data >= self.read_timeout_s
                                                              or now - self._cycle_since >= self.body_timeout_s):
            return self._close()
        self._arm()

    def _close(self) -> None:
        if self.cycle is not None and not self.cycle.response_complete:
            self.cycle.disconnected = True
            self.cycle.message_event.set()
        self.transport.close()
