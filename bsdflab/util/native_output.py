"""Capture what a native library prints while it runs (Python-level and file descriptors
1 and 2), so a damaged file gives one clear error instead of a screenful of diagnostics."""
from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
from collections.abc import Iterator


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
    """Silence stdout and stderr inside the block; the text lands in the yielded object."""
    captured = CapturedOutput()
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
