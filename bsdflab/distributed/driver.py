"""Run work units on a Dask cluster: submit, collect as they complete, show progress,
cancel on Ctrl-C.

Faults are Dask's business: units are pure, so a unit lost with a killed worker is simply
recomputed elsewhere (the nanny restarts the worker; the scheduler reschedules its tasks;
``retries`` covers units that raised on a sick worker). The driver only assembles results
as they arrive and never writes a file itself — callers write once, atomically, after the
last unit.
"""
from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable, Sequence
from typing import Any

# Reruns of a unit that raised (beyond the scheduler's own rescheduling of units whose
# worker died, which `distributed.scheduler.allowed-failures` bounds).
RETRIES = 2
POLL_S = 0.05


def token(*parts: Any) -> str:
    """A short content hash naming a job's units, so the same job's units share keys (a
    repeated submission reuses finished results) and different jobs never collide."""
    text = json.dumps(parts, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def run_units(client, fn: Callable[..., Any], shared: Sequence[Any], units: Sequence[Any],
              on_result: Callable[[Any, Any], None], *, name: str, progress: bool = True,
              desc: str = "units", progress_callback: Callable[[float], None] | None = None,
              cancelled: Callable[[], bool] | None = None) -> None:
    """Call ``fn(*shared, unit)`` for every unit on the cluster and ``on_result(unit, value)``
    on the driver as each finishes (in completion order: ``on_result`` must not depend on it).

    ``shared`` values are scattered once (broadcast) instead of being sent with every unit.
    Ctrl-C cancels every outstanding unit and re-raises KeyboardInterrupt; ``cancelled()``
    becoming true cancels them and raises JobCancelled.
    Inside a service job (a bsdflab.util.progress monitor), each finished unit is reported as the
    stage's progress and a cancelled job cancels its units (JobCancelled).
    """
    from distributed import as_completed

    from bsdflab.util.progress import JobCancelled, cancel_requested, report_progress

    # Wrapped in a list: scatter() would take a dict's items as separate pieces of data.
    # Fresh keys (hash=False): a content-hash key shared with an earlier, just-released
    # scatter of the same value could be forgotten under this job ("lost dependencies").
    shared_futures = [client.scatter([v], broadcast=True, hash=False)[0] for v in shared]
    futures = [client.submit(fn, *shared_futures, u, key=f"{name}-{i}", retries=RETRIES, pure=False)
               for i, u in enumerate(units)]
    unit_of = {f.key: u for f, u in zip(futures, units)}
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(units), unit="unit", desc=desc, leave=False)
    done = 0
    stop = cancelled or (lambda: False)
    try:
        pending = as_completed(futures)
        while not pending.is_empty():
            # Poll rather than block on the next unit, so a cancel is seen within POLL_S
            # even while every outstanding unit is long.
            if cancel_requested() or stop():
                raise JobCancelled(f"{desc} cancelled")
            batch = pending.next_batch(block=False)
            if not batch:
                time.sleep(POLL_S)
                continue
            for future in batch:
                on_result(unit_of[future.key], future.result())
                future.release()
                done += 1
                if bar is not None:
                    bar.update(1)
                report_progress(desc, done / len(units))
                if progress_callback is not None:
                    progress_callback(done / len(units))
    except BaseException:
        client.cancel(futures)
        raise
    finally:
        if bar is not None:
            bar.close()
        for f in shared_futures:
            f.release()
