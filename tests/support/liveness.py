"""One bound for every wait in the tests that only guards against a hang.

On a loaded machine (CI's 2 shared cores, a `stress --cpu 2` beside the suite) the work a
test waits for takes as long as the load makes it; only a real hang may fail the test, so
such waits use ``HANG_S`` and never a figure fitted to an idle machine. Seen on CI's load:
a SIGKILLed Dask worker's removal took ~60 s, and the old 60 s wait failed a correct run.
Timing is never asserted (docs/ARCHITECTURE.md, the `tests/` row).
"""
from __future__ import annotations

import time
from collections.abc import Callable

HANG_S = 600.0      # seconds; HANG_MS for Playwright's millisecond timeouts
HANG_MS = int(HANG_S * 1000)
POLL_S = 0.05       # how often a wait looks at its condition (polling, not synchronisation)


def wait_until(predicate: Callable[[], object], what: str, bound_s: float = HANG_S) -> None:
    """Return once ``predicate()`` is true; AssertionError naming ``what`` after ``bound_s``."""
    end = time.monotonic() + bound_s
    while not predicate():
        assert time.monotonic() < end, f"no {what} within {bound_s:g} s (a hang)"
        time.sleep(POLL_S)
