"""Registries by name whose entries may live in higher layers.

A registry maps a name to an object (a BSDF class, a runner class) that the object's own
module adds when it is imported (``BSDF.__init_subclass__``, ``register_runner``). A name
whose module sits *above* the registry's layer (``"table"`` in ``bsdflab.tables``, the
``"dask"`` runner in ``bsdflab.distributed``) is also given as a *lazy entry*: the module's
dotted path, imported the first time the name is asked for. Lookups then never depend on
what happened to be imported first, and the lower layer never imports upward at module
import time (joblib's ``register_parallel_backend`` and its lazy ``"dask"`` entry are the
model).
"""
from __future__ import annotations

import importlib
from typing import Any, Generic, TypeVar

T = TypeVar("T")


class Registry(Generic[T]):
    """Names -> objects, with lazy entries (name -> the module that registers it)."""

    def __init__(self, what: str, lazy: dict[str, str] | None = None):
        self.what = what
        self._items: dict[str, T] = {}
        self._lazy: dict[str, str] = dict(lazy or {})

    def add(self, name: str, item: T) -> None:
        self._items[name] = item

    def add_lazy(self, name: str, module: str) -> None:
        """``name`` is registered by importing ``module`` (a dotted path)."""
        self._lazy[name] = module

    def get(self, name: Any) -> T | None:
        """The entry for ``name`` (importing its module if it is lazy), or None."""
        if not isinstance(name, str):
            return None
        if name not in self._items and name in self._lazy:
            importlib.import_module(self._lazy[name])
        return self._items.get(name)

    def load_all(self) -> None:
        """Import every lazy entry's module (to search all entries)."""
        for name in list(self._lazy):
            self.get(name)

    def items(self) -> dict[str, T]:
        """The entries registered so far (lazy ones only once imported)."""
        return dict(self._items)

    def lazy(self) -> dict[str, str]:
        """The lazy entries: name -> the module that registers it."""
        return dict(self._lazy)

    def names(self) -> list[str]:
        """Every known name, lazy ones included, sorted."""
        return sorted(set(self._items) | set(self._lazy))
