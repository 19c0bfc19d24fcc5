"""Leave the process after Ctrl-C without the interpreter's teardown.

After Ctrl-C a normal exit spent 0.5-0.8 CPU-seconds in ``Py_FinalizeEx`` tearing down
the 1200-1800 modules a render or a fit loads (scipy, pandas, colour, matplotlib): perf
showed ``gc_collect_main`` and deallocators only, and at load ~10 that stretched to 4-5 s
of wall time. None of that teardown keeps a promise the command line makes: atomic
writes and the fit's temporary study folder are cleaned up by ``try``/``finally`` before
``main()`` returns, and the C++ jobs are stopped and waited for (bsdflab/util/progress.py).

So ``leave`` does the steps of ``Py_FinalizeEx`` that other code may rely on, in its
order, and ends the process with ``os._exit``:

1. wait for non-daemon threads, after threading's own exit hooks (concurrent.futures);
2. run the ``atexit`` handlers (logging, multiprocessing's children, ``weakref.finalize``
   such as temporary folders, Dask clients); each prints its own errors;
3. flush stdout and stderr.
"""
from __future__ import annotations

import atexit
import os
import sys
import threading
from typing import NoReturn


def leave(status: int) -> NoReturn:
    """End the process with ``status`` after the interpreter's exit steps that matter."""
    for step in (threading._shutdown, atexit._run_exitfuncs):
        try:
            step()
        except KeyboardInterrupt:  # another Ctrl-C ends that wait, not the exit (as CPython does)
            pass
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):  # a closed pipe or stream: nothing left to save
            pass
    os._exit(status)
