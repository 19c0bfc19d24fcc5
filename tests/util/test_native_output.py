"""Capturing native output swaps process-wide descriptors: concurrent captures must leave
stdout and stderr where they were, and a server can turn capture off."""
from __future__ import annotations

import os
import threading
import time

from bsdflab.util import native_output
from bsdflab.util.native_output import quiet_native_output


def targets() -> list[tuple[int, int]]:
    """The files descriptors 1 and 2 point at (device, inode)."""
    return [(os.fstat(fd).st_dev, os.fstat(fd).st_ino) for fd in (1, 2)]


def test_concurrent_captures_leave_the_descriptors_alone():
    """Before: 32 threads capturing at once left fd 1 or 2 pointing at a deleted temporary
    file (every later log line lost)."""
    before = targets()
    start = threading.Barrier(32)

    def capture(i: int):
        start.wait()
        for _ in range(5):
            with quiet_native_output() as noise:
                os.write(1, f"native {i}\n".encode())
                time.sleep(0.001 * (i % 3))
            assert f"native {i}" in noise.text

    threads = [threading.Thread(target=capture, args=(i,)) for i in range(32)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert targets() == before


def test_capture_off_touches_nothing(capfd):
    previous = native_output.capture_descriptors(False)
    try:
        with quiet_native_output() as noise:
            os.write(2, b"reaches the log\n")
        assert noise.text == "" and "reaches the log" in capfd.readouterr().err
    finally:
        native_output.capture_descriptors(previous)
