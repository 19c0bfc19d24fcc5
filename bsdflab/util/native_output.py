"""Capture what a native library prints while it runs (Python-level and file descriptors
1 and 2), so a damaged file gives one clear error instead of a screenful of diagnostics.

Capturing swaps the process-wide descriptors 1 and 2 (``dup2``): two threads doing it at
once could leave them pointing at a deleted temporary file, and while one thread holds
them every other thread's output lands in its capture. So the swap is serialised by a
lock, and a threaded server turns it off altogether (``capture_descriptors(False)``, as
the HTTP service does while it runs): the block then captures nothing, and a native
library's diagnostics reach the server's log like any other line."""
from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
import threading
from collections.abc import Iterator

_SWAP = threading.Lock()
_enabled = True


def capture_descriptors(enabled: bool) -> bool:
    """Turn descriptor capture on or off for the whole process; returns the previous state."""
    global _enabled
    previous, _enabled = _enabled, bool(enabled)
    return previous


class CapturedOutput:
    """Text printed inside `quiet_native_output` (available after the block)."""

    def __init__(self) -> None:
        self.text = ""

    def first_line(self) -> str:
        return next((line.strip() for line in self.text.splitlines() if line.strip()), "")


def _flush_c_stdio() -> None:
    try:
        import ctypes

        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):  # no C runtime to flush (not POSIX)
        pass


@contextlib.contextmanager
def quiet_native_output() -> Iterator[CapturedOutput]:
    """Silence stdout and stderr inside the block; the text lands in the yielded object
    (nothing is silenced, and nothing captured, while ``capture_descriptors`` is off)."""
    captured = CapturedOutput()
    if not _enabled:
        yield captured
        return
    with _SWAP:
        yield from _swapped(captured)


def _swapped(captured: CapturedOutput) -> Iterator[CapturedOutput]:
    python_text = io.StringIO()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    saved: list[tuple[int, int]] = []
    with tempfile.TemporaryFile() as sink:
        try:
            for fd in (1, 2):
                try:
                    saved.append((fd, os.dup(fd)))
                except OSError:  # descriptor closed: nothing to silence
                    continue
                os.dup2(sink.fileno(), fd)
            with contextlib.redirect_stdout(python_text), contextlib.redirect_stderr(python_text):
                yield captured
        finally:
            _flush_c_stdio()
            for fd, copy in saved:
                os.dup2(copy, fd)
                os.close(copy)
            sink.seek(0)
            # The native library's own lines first: they are the most specific.
            captured.text = sink.read().decode("utf-8", "replace") + python_text.getvalue()
