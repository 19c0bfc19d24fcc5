"""Run a long C++ job (tabulation, rendering) with a progress bar and clean Ctrl-C.

The job object needs ``run()`` (releases the GIL), ``cancel()``, ``total`` and ``done``.
"""
from __future__ import annotations

import threading


def run_with_progress(job, show: bool, unit: str, desc: str) -> None:
    """Run the job on a worker thread (the core releases the GIL) while the main thread
    draws the progress bar; Ctrl-C cancels the job, waits for it to stop and re-raises.

    The main thread waits on an Event, not on Thread.join: on CPython < 3.13 a Ctrl-C
    inside join() can mark the still-running thread as finished (python/cpython#90882),
    so a later join() returns at once and the interpreter exits under the running job,
    which aborts the process (SIGABRT from the GIL hand-back at shutdown)."""
    error: list[BaseException] = []
    finished = threading.Event()

    def work():
        try:
            job.run()
        except BaseException as e:  # surfaced on the main thread below
            error.append(e)
        finally:
            finished.set()

    worker = threading.Thread(target=work, name=f"bsdflab-{desc}", daemon=True)
    worker.start()
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=job.total, unit=unit, desc=desc, leave=False)
    try:
        while not finished.wait(0.2):
            if bar is not None:
                bar.n = job.done
                bar.refresh()
    except KeyboardInterrupt:
        job.cancel()
        while True:  # the job stops after its current work items; never leave it running
            try:
                finished.wait()
                break
            except KeyboardInterrupt:
                continue
        raise
    finally:
        if bar is not None:
            bar.close()
    if error:
        raise error[0]
