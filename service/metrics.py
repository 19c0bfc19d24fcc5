"""Prometheus metrics at ``/metrics`` (prometheus-client; one registry per application).

Request latency histograms per route template and status; heavy requests in flight and
refused; the job queue's depth and jobs by state and kind (read from the store at each
scrape); walks evaluated (``rate(bsdflab_eval_walks_total[1m])`` is walks per second).
With keys configured, only an admin key may read them.
"""
from __future__ import annotations

import time

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import Response
from prometheus_client import CONTENT_TYPE_LATEST, CollectorRegistry, Counter, Histogram, generate_latest
from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily

router = APIRouter(tags=["meta"])
LATENCY_BUCKETS = (0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30)
# Label values come from a fixed set: a client's method name or path never becomes a new
# time series (2000 random methods once grew /metrics to 259 MB).
KNOWN_METHODS = frozenset({"GET", "HEAD", "POST", "PUT", "PATCH", "DELETE", "OPTIONS"})
OTHER = "other"


class Metrics:
    def __init__(self):
        self.registry = CollectorRegistry()
        self.latency = Histogram("bsdflab_http_request_duration_seconds", "request latency by route",
                                 ("method", "route", "status"), buckets=LATENCY_BUCKETS, registry=self.registry)
        self.walks = Counter("bsdflab_eval_walks", "Monte Carlo walks evaluated by requests",
                             registry=self.registry)
        self.app = None

    def bind(self, app) -> None:
        """Read the heavy pool and the job store of ``app`` at each scrape."""
        self.app = app
        self.registry.register(_State(app))


class _State:
    def __init__(self, app):
        self.app = app

    def collect(self):
        heavy = self.app.state.heavy
        yield GaugeMetricFamily("bsdflab_heavy_in_flight", "computing requests running", value=heavy.in_flight)
        yield GaugeMetricFamily("bsdflab_heavy_slots", "computing requests allowed at once", value=heavy.size)
        yield CounterMetricFamily("bsdflab_heavy_refused", "computing requests refused (429)", value=heavy.refused)
        jobs = getattr(self.app.state, "jobs", None)
        if jobs is None:
            return
        by_state = GaugeMetricFamily("bsdflab_jobs", "jobs in the store by kind and state", labels=("kind", "state"))
        depth = 0
        for kind, state, n in jobs.store.counts():
            by_state.add_metric((kind, state), n)
            depth += n if state in ("queued", "running") else 0
        yield by_state
        yield GaugeMetricFamily("bsdflab_job_queue_depth", "queued and running jobs", value=depth)


class Timing:
    """ASGI middleware: observe each request's latency under its route template."""

    def __init__(self, app, metrics: Metrics):
        self.app, self.metrics = app, metrics

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        status, start = 0, time.perf_counter()

        async def seen(message):
            nonlocal status
            if message["type"] == "http.response.start":
                status = message["status"]
            await send(message)

        try:
            await self.app(scope, receive, seen)
        finally:
            route = scope.get("route")
            template = getattr(route, "path", None) or "unmatched"   # route templates: a fixed set
            method = scope["method"] if scope["method"] in KNOWN_METHODS and template != "unmatched" else OTHER
            self.metrics.latency.labels(method, template, str(status)).observe(time.perf_counter() - start)


@router.get("/metrics", include_in_schema=False)
def metrics(request: Request) -> Response:
    client = request.scope.get("state", {}).get("client")
    if client is None or not client.admin:
        raise HTTPException(403, "metrics are for an admin key")
    return Response(generate_latest(request.app.state.metrics.registry), media_type=CONTENT_TYPE_LATEST)
