"""The command line's exit after Ctrl-C (bsdflab/cli/leave.py): it skips the interpreter's
teardown (0.5-0.8 CPU-seconds, 4-5 s of wall time at load ~10) but keeps every step of it
that other code relies on."""
from __future__ import annotations

import os
import subprocess
import sys

# The child runs what the console script runs (`sys.exit(main())`, no argv) with
# `bsdflab info` replaced by a command that prints and is interrupted, and with one witness
# for each exit step: a non-daemon thread that ends only after the main thread has (CPython
# releases the main thread to joiners on shutdown), an atexit handler, a temporary folder
# left to its weakref.finalize, unflushed stdout, and an object freed only by the teardown.
CHILD = r"""
import atexit, os, sys, tempfile, threading
import bsdflab.cli.info

out = sys.argv[1]


def touch(name):
    open(os.path.join(out, name), "w").close()


class FreedByTeardown:
    def __del__(self, write=os.write):
        write(2, b"teardown ran\n")


sentinel = FreedByTeardown()
left_behind = tempfile.TemporaryDirectory(dir=out)
threading.Thread(target=lambda: (threading.main_thread().join(), touch("thread"))).start()
atexit.register(touch, "atexit")


def interrupted(args):
    sys.stdout.write("unflushed output")  # no newline, and stdout is a pipe: still buffered
    raise KeyboardInterrupt


bsdflab.cli.info.run = interrupted
sys.argv = ["bsdflab", "info"]
from bsdflab.cli.main import main
sys.exit(main())
"""


def test_interrupted_exit_keeps_the_exit_steps_and_skips_the_teardown(tmp_path):
    """Status 130, the one line exactly, stdout flushed, the atexit handler and the
    temporary folder's finaliser run, the non-daemon thread finished, and no teardown.
    Mutations: leave() without threading._shutdown (no `thread`), without the atexit
    handlers (no `atexit`, the temporary folder left), without the flush (stdout empty);
    main() without leave() (the teardown's line on stderr)."""
    buffered = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}  # set by some CI shells
    r = subprocess.run([sys.executable, "-c", CHILD, str(tmp_path)], capture_output=True, text=True,
                       env=buffered, timeout=300)  # a hang guard only
    assert (r.returncode, r.stderr) == (130, "\nbsdflab info: interrupted\n"), (r.returncode, r.stderr[-2000:])
    assert r.stdout == "unflushed output"
    assert sorted(os.listdir(tmp_path)) == ["atexit", "thread"]
