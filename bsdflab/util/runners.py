"""Runners: where a feature's work units run, so that features never name a cluster.

A feature splits its work into *units*, pure functions of plain data
(``bsdflab.tables.units``, ``bsdflab.render.units``), and hands them to a runner::

    runner.run(fn, shared, units, on_result, key="bsdflab-render-<hash>", desc="rendering")

calls ``fn(*shared, unit)`` for every unit and ``on_result(unit, value)`` here as each one
finishes, in any order (``on_result`` must not depend on it). While it runs it shows a
progress bar (``progress=True``), reports each finished unit to the job monitor
(``bsdflab.util.progress``) and to ``progress_callback(fraction)``, and stops with
``JobCancelled`` once the monitor or ``cancelled()`` asks; Ctrl-C cancels what is
outstanding and re-raises.

Runners are registered by name (``Runner.name``), as BSDF types are: ``"local"``
(``LocalRunner``, this process, one unit after another) is defined here; ``"dask"``
(``bsdflab.distributed.runner.DaskRunner``) registers itself from the layer above, and is
a lazy entry here so that looking it up imports it. The job layer turns an executor spec
``"<runner>:<target>"`` into jobs whose units run on ``open_runner(spec)``.

=========  ========================================  ==============================
name       ``Runner.connect(target)``                ``RunnerClass(obj)``
=========  ========================================  ==============================
local      ``"local"`` (no target)                   ``LocalRunner()``
dask       ``"tcp://HOST:8786"`` or ``"local:N"``    ``DaskRunner(client)``
=========  ========================================  ==============================
"""
from __future__ import annotations

import abc
import contextlib
import hashlib
import json
from collections.abc import Callable, Iterator, Sequence
from typing import Any, ClassVar

from bsdflab.util.progress import JobCancelled, cancel_requested, report_progress
from bsdflab.util.registry import Registry

RUNNERS: Registry[type[Runner]] = Registry("runner", lazy={"dask": "bsdflab.distributed.runner"})


class Runner(abc.ABC):
    """Runs work units (module docstring). Subclasses set ``name`` to register."""

    name: ClassVar[str] = ""

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        # Only a class that names itself: a subclass inheriting its parent's name would
        # otherwise replace the parent in the registry.
        if cls.__dict__.get("name"):
            RUNNERS.add(cls.name, cls)

    @abc.abstractmethod
    def run(self, fn: Callable[..., Any], shared: Sequence[Any], units: Sequence[Any],
            on_result: Callable[[Any, Any], None], *, key: str, desc: str = "units",
            progress: bool = True, progress_callback: Callable[[float], None] | None = None,
            cancelled: Callable[[], bool] | None = None) -> None:
        """Call ``fn(*shared, unit)`` for every unit, ``on_result(unit, value)`` for each
        result. ``key`` names this batch of units (``unit_key``): a cluster may reuse a
        finished unit of the same key."""

    def workers(self) -> int:
        """How many workers share the units (recorded in results' metadata)."""
        return 1

    @classmethod
    @contextlib.contextmanager
    def connect(cls, target: str) -> Iterator[Runner]:
        """A runner for ``target`` (the part of an executor spec after ``name:``), closed
        on exit."""
        raise ValueError(f"the {cls.name!r} runner takes no target, got {target!r}")
        yield  # pragma: no cover -- makes this a generator


class LocalRunner(Runner):
    """Units one after another in this process (each unit uses every core through the C++
    core): the units' results without a cluster, e.g. to check a unit split."""

    name = "local"

    def run(self, fn, shared, units, on_result, *, key, desc="units", progress=True,
            progress_callback=None, cancelled=None) -> None:
        stop = cancelled or (lambda: False)
        with progress_bar(len(units), desc, progress) as bar:
            for done, unit in enumerate(units, 1):
                if cancel_requested() or stop():
                    raise JobCancelled(f"{desc} cancelled")
                on_result(unit, fn(*shared, unit))
                finished_unit(bar, desc, done / len(units), progress_callback)

    @classmethod
    @contextlib.contextmanager
    def connect(cls, target: str) -> Iterator[Runner]:
        if target not in ("", "local"):
            raise ValueError(f"the local runner takes no target, got {target!r}")
        yield cls()


@contextlib.contextmanager
def progress_bar(total: int, desc: str, show: bool) -> Iterator[Any]:
    """A tqdm bar over ``total`` units on stderr (None when not ``show``), closed on exit."""
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=total, unit="unit", desc=desc, leave=False)
    try:
        yield bar
    finally:
        if bar is not None:
            bar.close()


def finished_unit(bar, desc: str, fraction: float, callback: Callable[[float], None] | None) -> None:
    """Tell the bar, the job monitor and ``callback`` that a unit finished."""
    if bar is not None:
        bar.update(1)
    report_progress(desc, fraction)
    if callback is not None:
        callback(fraction)


def unit_key(*parts: Any) -> str:
    """A short content hash naming a job's units, so the same job's units share keys (a
    repeated submission reuses finished results) and different jobs never collide."""
    text = json.dumps(parts, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def get_runner(name: str) -> type[Runner]:
    """The runner class registered as ``name``; ValueError naming the known ones."""
    cls = RUNNERS.get(name)
    if cls is None:
        raise ValueError(f"unknown runner {name!r}; known: {', '.join(RUNNERS.names())}")
    return cls


def resolve(runner: Runner | None = None, client: Any = None) -> Runner | None:
    """The runner an API call was given: ``runner``, or for ``client`` (a
    ``dask.distributed.Client``, the convenience) the registered ``"dask"`` runner over it;
    None for the caller's own in-process path."""
    if runner is not None and client is not None:
        raise ValueError("give runner or client, not both")
    if client is not None:
        return get_runner("dask")(client)
    if runner is not None and not isinstance(runner, Runner):
        raise ValueError(f"runner must be a bsdflab.util.runners.Runner, got {type(runner).__name__}")
    return runner


@contextlib.contextmanager
def open_runner(spec: str) -> Iterator[Runner]:
    """The runner named by ``spec`` = ``"<name>:<target>"`` (``"dask:tcp://HOST:8786"``,
    ``"dask:local:2"``) or ``"<name>"``, connected; closed on exit."""
    name, _, target = spec.strip().partition(":")
    with get_runner(name).connect(target) as runner:
        yield runner
