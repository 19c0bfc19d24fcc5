"""Job kinds for testing executors (registered by the tests, run in worker processes):
"sleep" reports progress in steps and honours cancel, "crash" kills its process,
"fail" raises a ValueError. Not product kinds."""
from __future__ import annotations

import hashlib
import json
import os
import time

from bsdflab.jobs import JobCancelled


def normalise(request):
    return dict(request)


def key(request):
    return hashlib.sha256(json.dumps(request, sort_keys=True).encode()).hexdigest()


def existing(request, out_dir):
    return None


def run(request, out_dir, progress, cancelled, client=None):
    action = request.get("action", "sleep")
    if action == "crash":
        os._exit(3)
    if action == "fail":
        raise ValueError("the request asked to fail")
    steps = int(request.get("steps", 10))
    for i in range(steps):
        if cancelled():
            raise JobCancelled("stopped")
        progress(i / steps)
        time.sleep(float(request.get("step_s", 0.05)))
    return {"hash": key(request), "pid": os.getpid(), "files": {}}


def never_ready(conn, cancel, parent_pid, warm=True):
    """A worker target that never says "ready" (a worker still in its imports, forever)."""
    while True:
        time.sleep(60)
