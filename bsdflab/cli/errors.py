"""How the command line fails: one line on stderr naming the problem, and an exit status.

Exit status 2 for anything the user can fix (bad parameters, unreadable or unwritable
files, inputs too large for the caps, nesting too deep), 130 after Ctrl-C (SIGINT), as
shells do. Only a bug in bsdflab itself shows a traceback.
"""
from __future__ import annotations

import errno
import os
import sys

from bsdflab.util.args import one_line

USAGE_ERROR = 2
INTERRUPTED = 130


def describe_os_error(e: OSError) -> str:
    """'<file>: <reason>' for an OSError, without the errno noise."""
    reason = e.strerror or errno.errorcode.get(e.errno or 0, "") or str(e)
    names = [n for n in (e.filename, e.filename2) if n]
    return f"{' -> '.join(map(os.fsdecode, names))}: {reason}" if names else reason


def run_command(args) -> int:
    """Run ``args.run(args)`` and turn failures into a message and an exit status."""
    name = f"bsdflab {args.command}"
    try:
        return int(args.run(args) or 0)
    except KeyboardInterrupt:
        # On a line of its own: a progress bar cut off mid-line has written no newline.
        print(f"\n{name}: interrupted", file=sys.stderr)
        return INTERRUPTED
    except ValueError as e:  # bad input: a clear message, not a traceback
        message = one_line(e, 2000)
    except ImportError as e:  # an optional dependency (bsdflab.util.extras names its extra)
        message = one_line(e, 2000)
    except OSError as e:  # a file we could not read or write
        message = describe_os_error(e)
    except RecursionError:
        message = "the input is nested too deeply"
    except MemoryError:
        message = "out of memory (lower the request, or the caps in bsdflab.util.limits)"
    print(f"{name}: error: {message}", file=sys.stderr)
    return USAGE_ERROR


def check_writable(path: str, option: str) -> None:
    """Refuse an output path that cannot be written, before any work starts: a folder, a
    file in a folder that cannot be created or written, or a read-only file."""
    target = os.path.abspath(os.fspath(path))
    if os.path.isdir(target):
        raise ValueError(f"{option} {path} is a folder, not a file")
    folder = os.path.dirname(target)
    existing = folder
    while not os.path.isdir(existing):  # the nearest folder that exists
        if os.path.exists(existing):
            raise ValueError(f"{option} {path}: {existing} is not a folder")
        existing = os.path.dirname(existing)
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {path}: cannot write in {existing} (permission denied)")
    if os.path.exists(target) and not os.access(target, os.W_OK):
        raise ValueError(f"{option} {path} exists and is read-only")
