"""API keys that scope: who a request is, checked before its body is read.

Keys come from the settings: ``api_key`` (one admin key, named "admin") and ``api_keys`` /
``api_keys_file`` (JSON: ``{"name": {"key": "...", "admin": false, "max_jobs": 8,
"rate_per_s": 20}}``). With no key configured the service is open and every request is the
anonymous admin. With keys, `KeyCheck` (an ASGI middleware, so it runs before any body is
received) answers 401 to a request without a valid key, except on the public paths: health,
the page and its static files, and the API's documentation (the schema holds no data). A
known client over its request rate gets 429 with ``Retry-After`` (the public paths take
nothing from the rate: a busy client's health checks still answer). The client is left in
``scope["state"]["client"]`` for the routes: jobs belong to the client that created them
(an admin sees all), and each client has its own share of the job queue.
"""
from __future__ import annotations

import hmac
import json
import math
import threading
import time
from dataclasses import dataclass
from pathlib import Path

PUBLIC_PATHS = frozenset({"/healthz", "/", "/vendor/plotly.min.js", "/docs", "/docs/oauth2-redirect",
                          "/redoc", "/openapi.json"})
PUBLIC_PREFIXES = ("/static/", "/vendor/")
UNAUTHORISED = "a valid API key is required (X-API-Key header or Bearer token)"


@dataclass(frozen=True)
class Client:
    """Who sent a request, and what it may use."""

    name: str
    admin: bool = False
    max_jobs: int | None = None      # active jobs of this client (None: the whole queue)
    rate_per_s: float | None = None  # requests per second, bursts of twice that (None: no limit)


ANONYMOUS = Client("anonymous", admin=True)


def load_clients(settings) -> dict[bytes, Client]:
    """Key bytes -> client, from the settings (ValueError naming the setting when malformed)."""
    entries: dict[str, dict] = {}
    if settings.api_keys_file is not None:
        try:
            entries.update(json.loads(Path(settings.api_keys_file).read_text()))
        except (OSError, ValueError) as e:
            raise ValueError(f"BSDFLAB_API_KEYS_FILE: cannot read a JSON object of keys: {e}") from None
    entries.update(settings.api_keys or {})
    clients: dict[bytes, Client] = {}
    if settings.api_key is not None:   # the single key of earlier versions: an admin
        clients[settings.api_key.get_secret_value().encode()] = Client("admin", admin=True)
    for name, entry in entries.items():
        entry = {"key": entry} if isinstance(entry, str) else dict(entry)
        key = entry.pop("key", None)
        if not isinstance(key, str) or len(key) < 16:
            raise ValueError(f"API key {name!r}: 'key' must be a string of at least 16 characters")
        unknown = set(entry) - {"admin", "max_jobs", "rate_per_s"}
        if unknown:
            raise ValueError(f"API key {name!r}: unknown fields {sorted(unknown)}")
        rate = entry.get("rate_per_s", settings.key_rate_per_s)
        admin = bool(entry.get("admin", False))
        # a client is its name (its jobs and uploads are recorded by it): two keys under one
        # name, one of them BSDFLAB_API_KEY's admin, shared everything (and one key named twice
        # was whichever came last)
        other = clients.get(key.encode())
        if other is not None or (name == "admin" and settings.api_key is not None and not admin):
            raise ValueError(f"API key {name!r}: " + (f"the same key as {other.name!r}" if other is not None else
                                                       "the name 'admin' is BSDFLAB_API_KEY's; name it otherwise"))
        clients[key.encode()] = Client(name, admin,
                                       entry.get("max_jobs", None if admin else settings.limit_queue_per_key),
                                       None if admin and "rate_per_s" not in entry else rate)
    return clients


class _Buckets:
    """A token bucket per client: ``rate`` tokens a second, at most ``2 rate`` saved."""

    def __init__(self):
        self._state: dict[str, tuple[float, float]] = {}
        self._lock = threading.Lock()

    def take(self, client: Client) -> float:
        """0 when the request may go, else the seconds until it may."""
        if client.rate_per_s is None:
            return 0.0
        rate, burst = client.rate_per_s, max(1.0, 2 * client.rate_per_s)
        now = time.monotonic()
        with self._lock:
            tokens, then = self._state.get(client.name, (burst, now))
            tokens = min(burst, tokens + (now - then) * rate)
            if tokens < 1:
                self._state[client.name] = (tokens, now)
                return (1 - tokens) / rate
            self._state[client.name] = (tokens - 1, now)
            return 0.0


def is_public(path: str) -> bool:
    return path in PUBLIC_PATHS or path.startswith(PUBLIC_PREFIXES)


def given_key(headers: list[tuple[bytes, bytes]]) -> bytes | None:
    found = {}
    for name, value in headers:
        name = name.lower()
        if name in (b"x-api-key", b"authorization") and name not in found:
            found[name] = value
    if b"x-api-key" in found:
        return found[b"x-api-key"]
    scheme, _, token = found.get(b"authorization", b"").partition(b" ")
    return token.strip() if scheme.lower() == b"bearer" and token.strip() else None


class KeyCheck:
    """ASGI middleware: identify the client from its key before anything else runs."""

    def __init__(self, app, clients: dict[bytes, Client], reply):
        self.app, self.clients, self.reply = app, clients, reply
        self.buckets = _Buckets()

    def identify(self, key: bytes | None) -> Client | None:
        """The key's client, comparing with every key in constant time."""
        found = None
        for known, client in self.clients.items():
            if hmac.compare_digest(known, key or b"") and key is not None:
                found = client
        return found

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        state = scope.setdefault("state", {})
        if not self.clients:
            state["client"] = ANONYMOUS
            return await self.app(scope, receive, send)
        client = self.identify(given_key(scope.get("headers") or []))
        if is_public(scope["path"]):   # health, the page, the docs: no key needed, no rate taken
            if client is not None:
                state["client"] = client
            return await self.app(scope, receive, send)
        if client is None:
            return await self.reply(send, 401, UNAUTHORISED, {"WWW-Authenticate": "Bearer"})
        wait = self.buckets.take(client)
        if wait > 0:
            return await self.reply(send, 429, f"client {client.name!r} is over its rate of {client.rate_per_s:g} "
                                               "requests per second; retry later",
                                    {"Retry-After": str(max(1, math.ceil(wait)))})
        state["client"] = client
        return await self.app(scope, receive, send)
