"""Computing requests under a bounded concurrency, a deadline and the client's attention.

Routes that compute (evaluations, lobes, figures, film spectra) run on their own thread
pool of ``heavy_concurrency`` threads (default: the cores), never on the pool FastAPI uses
for plain routes, and ``/healthz`` is a coroutine: health never waits on computation. When
every slot is busy a request is answered 429 with ``Retry-After`` at once instead of
queueing. Each computation runs under ``bsdflab.util.progress.monitored`` (the jobs'
cancellation): it stops when the compute deadline passes or the client disconnects, at
the next boundary between C++ calls (`evaluate_in_chunks` splits a large evaluation into
calls of at most ``CHUNK_WALKS`` walks, so the boundary comes within about a second).
"""
from __future__ import annotations

import asyncio
import contextlib
import contextvars
import os
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, TypeVar

import numpy as np
from fastapi import HTTPException, Request

from bsdflab import slices
from bsdflab.layered.stack import ERROR_WALKS_PER_SAMPLE
from bsdflab.util.progress import JobCancelled, cancel_requested, monitored

T = TypeVar("T")
CHUNK_WALKS = 1 << 14       # walks per C++ call of a stochastic evaluation (~1 CPU-second)
CHUNK_PAIRS = 1 << 16       # pairs per C++ call of a deterministic one
POLL_S = 0.05               # how often a waiting request looks at its client


def default_concurrency() -> int:
    return max(1, os.cpu_count() or 1)


class HeavyPool:
    """At most ``size`` computing requests at once, each on this pool's own threads."""

    def __init__(self, size: int, deadline_s: float, retry_after_s: int = 1):
        self.size, self.deadline_s, self.retry_after_s = size, deadline_s, retry_after_s
        self.in_flight = 0       # touched from the event loop only
        self.refused = 0
        self._threads = ThreadPoolExecutor(max_workers=size, thread_name_prefix="bsdflab-heavy")

    async def run(self, request: Request, fn: Callable[..., T], *args: Any) -> T:
        """``fn(*args)`` on a heavy thread; 429 when full, 422 past the deadline; stops (and
        answers nothing useful) when the client goes away."""
        if self.in_flight >= self.size:
            self.refused += 1
            raise HTTPException(429, f"all {self.size} computing slots are busy (BSDFLAB_HEAVY_CONCURRENCY); "
                                     "retry later", headers={"Retry-After": str(self.retry_after_s)})
        self.in_flight += 1
        stop = threading.Event()
        deadline = time.monotonic() + self.deadline_s

        def cancelled() -> bool:
            return stop.is_set() or time.monotonic() > deadline

        def work():
            with monitored(lambda stage, fraction: None, cancelled):
                return fn(*args)

        try:
            # the request's context (its id for the log lines) goes with the work
            future = asyncio.get_running_loop().run_in_executor(self._threads, contextvars.copy_context().run, work)
            while True:
                done, _ = await asyncio.wait({future}, timeout=POLL_S)
                if done:
                    break
                if await _disconnected(request):
                    stop.set()
            try:
                return future.result()
            except JobCancelled:
                if stop.is_set():   # nobody is listening; the status is for the log only
                    raise HTTPException(499, "client closed the request") from None
                raise HTTPException(422, f"the computation took longer than the deadline of {self.deadline_s:g} s "
                                         "(BSDFLAB_COMPUTE_DEADLINE_S): ask for fewer pairs, walks or points") from None
        finally:
            self.in_flight -= 1

    def close(self) -> None:
        self._threads.shutdown(wait=False, cancel_futures=True)


async def _disconnected(request: Request) -> bool:
    with contextlib.suppress(Exception):
        return await request.is_disconnected()
    return False


def check_cancelled() -> None:
    if cancel_requested():
        raise JobCancelled("cancelled")


def evaluate_in_chunks(bsdf, wi: np.ndarray, wo: np.ndarray, wavelengths, samples: int | None,
                       seed: int | None, thickness: np.ndarray | None = None) -> slices.Values:
    """``slices.evaluate`` over the pairs in pieces, looking for a cancellation between them.
    Walks are seeded per pair from (seed, wi, wo), so the pieces give the same numbers as
    one call."""
    pairs = max(len(wi), len(wo))
    wi, wo = np.broadcast_to(wi, (pairs, 3)), np.broadcast_to(wo, (pairs, 3))
    if thickness is not None:
        thickness = np.broadcast_to(np.asarray(thickness, dtype=float), (pairs,))
    if slices.is_stochastic(bsdf):
        # each walk of the value brings ERROR_WALKS_PER_SAMPLE walks for its error (Layered.estimate)
        walks = (samples if samples is not None else bsdf.samples) * (1 + ERROR_WALKS_PER_SAMPLE)
        step = max(1, CHUNK_WALKS // walks)
    else:
        step = CHUNK_PAIRS
    values, errors = [], []
    for start in range(0, pairs, step):
        check_cancelled()
        part = slices.evaluate(bsdf, wi[start:start + step], wo[start:start + step], wavelengths, samples, seed,
                               None if thickness is None else thickness[start:start + step])
        values.append(part.values)
        errors.append(part.stderr)
    stderr = None if errors[0] is None else np.concatenate(errors)
    return slices.Values(np.concatenate(values), stderr)
