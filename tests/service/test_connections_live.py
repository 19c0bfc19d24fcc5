"""Finding M11 of issue 33, against a real ``bsdflab serve``: idle and slow connections are
closed, and ``/healthz`` answers even with the connection cap reached. Before: 40 idle
sockets (cap 40) made /healthz answer 503 for as long as they stayed, which was for ever."""
from __future__ import annotations

import socket

import httpx2 as httpx
import pytest

from support.liveness import HANG_S
from support.service_process import ServiceProcess

CAP = 4


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    env = {"BSDFLAB_SERVER_LIMIT_CONCURRENCY": str(CAP), "BSDFLAB_SERVER_HEADER_TIMEOUT_S": "1",
           "BSDFLAB_SERVER_READ_TIMEOUT_S": "1", "BSDFLAB_SERVER_BODY_TIMEOUT_S": "2",
           "BSDFLAB_EXECUTOR": "threads"}
    process = ServiceProcess(tmp_path_factory.mktemp("connections"), env=env)
    yield process
    process.stop()


def _open(server, first: bytes = b"") -> socket.socket:
    s = socket.create_connection(("127.0.0.1", server.port), timeout=HANG_S)
    if first:
        s.sendall(first)
    return s


def _closed_by_server(s: socket.socket) -> bool:
    """True when the server closes the socket (recv answers b"" or a reset) within the
    socket's HANG_S timeout (a liveness bound); the server's timeout is 1 s."""
    try:
        while s.recv(4096):
            pass
        return True
    except ConnectionResetError:
        return True
    except TimeoutError:
        return False


def test_healthz_answers_at_the_connection_cap_and_idle_sockets_close(server):
    """Mutation caught: uvicorn's own ``limit_concurrency`` (healthz 503) or no header
    deadline (the idle sockets are never closed: the recv times out after HANG_S)."""
    idle = [_open(server) for _ in range(CAP + 2)]
    slow_headers = _open(server, b"GET /v1/presets HTTP/1.1\r\nHost: x\r\n")        # never finishes its headers
    slow_body = _open(server, b"POST /v1/thinfilm/spectrum HTTP/1.1\r\nHost: x\r\nContent-Type: application/json"
                              b"\r\nContent-Length: 100\r\n\r\n{")                 # never finishes its body
    try:
        with httpx.Client(base_url=server.url, timeout=HANG_S) as client:
            assert client.get("/healthz").status_code == 200
            assert client.get("/v1/presets").status_code == 503
        assert all(_closed_by_server(s) for s in [*idle, slow_headers, slow_body])
        with httpx.Client(base_url=server.url, timeout=HANG_S) as client:
            assert client.get("/v1/presets").status_code == 200
    finally:
        for s in [*idle, slow_headers, slow_body]:
            s.close()


def test_a_trickled_body_is_closed_at_the_body_deadline(server):
    """A body sent a byte every 0.2 s never stalls for the 1 s read timeout; before, such an
    upload held its declared size of the upload bytes in flight for ever (every other
    tenant's upload: 429). The server closes it at the 2 s body deadline; the loop is
    bounded at 60 s. Mutation caught: no body deadline (the trickle runs the whole 60 s)."""
    s = _open(server, b"POST /v1/measured?format=merl HTTP/1.1\r\nHost: x\r\nContent-Type: "
                      b"application/octet-stream\r\nContent-Length: 100000\r\n\r\n")
    s.settimeout(0.2)
    closed = False
    try:
        for _ in range(300):
            try:
                s.sendall(b"x")
                if s.recv(4096) == b"":
                    closed = True
                    break
            except TimeoutError:
                continue
            except OSError:
                closed = True
                break
    finally:
        s.close()
    assert closed
