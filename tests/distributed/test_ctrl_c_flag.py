"""Ctrl-C while DaskRunner.run polls its units on the main thread (a real LocalCluster of one
worker process): SIGINT sets a flag that the poll loop reads, and no Ctrl-C is lost or
swallowed. The signal is raised by the result callback itself (``signal.raise_signal``
runs the Python handler before it returns), so where it lands is fixed, not a race.
"""

from __future__ import annotations

import signal

import pytest

from bsdflab.distributed import DaskRunner, connect
from support.liveness import HANG_S


@pytest.fixture(scope="module")
def client():
    with connect(cluster="local:1") as c:
        c.wait_for_workers(1, timeout=HANG_S)
        yield c


@pytest.fixture
def default_sigint():
    """The interpreter's own SIGINT handler (the runner leaves another one alone)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_a_ctrl_c_during_the_last_result_is_not_lost(client, default_sigint):
    """Before: a Ctrl-C that came after the loop's last look at the flag (while the last
    unit's result was handled) was dropped: run returned as if never interrupted, and the
    program went on. Now it raises KeyboardInterrupt once the loop ends, and the handler
    is the interpreter's again."""
    received = []

    def on_result(unit, value):
        received.append(value)
        if len(received) == 2:
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        DaskRunner(client).run(abs, [], [-1, -2], on_result, key="ctrl-c-last", progress=False)
    assert sorted(received) == [1, 2]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_second_ctrl_c_interrupts_at_once(client, default_sigint):
    """Before: while the loop was held elsewhere (a slow result callback, a result fetched
    from a busy worker), every further Ctrl-C only set the flag again: nothing could stop
    the driver until the loop came round. Now the second raises KeyboardInterrupt where
    the driver is (here: inside the callback, which goes no further)."""
    went_on = []

    def on_result(unit, value):
        signal.raise_signal(signal.SIGINT)
        signal.raise_signal(signal.SIGINT)
        went_on.append(unit)

    with pytest.raises(KeyboardInterrupt):
        DaskRunner(client).run(abs, [], [-1, -2], on_result, key="ctrl-c-twice", progress=False)
    assert went_on == []
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
