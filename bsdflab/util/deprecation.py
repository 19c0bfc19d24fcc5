"""Old names kept working for a while, each use announced by a FutureWarning (shown by
default, unlike DeprecationWarning, so users of the library see it, not only its tests)."""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from typing import Any


def warn_renamed(what: str, old: str, new: str, stacklevel: int = 3) -> None:
    """Warn that ``what`` ``old`` is now called ``new`` (stacklevel 3: the caller's caller)."""
    warnings.warn(f"{what} {old!r} is deprecated: it is now called {new!r}", FutureWarning, stacklevel=stacklevel)


def renamed_attributes(module: str, renamed: dict[str, tuple[str, Any]]) -> Callable[[str], Any]:
    """A module ``__getattr__`` serving each old name of ``renamed`` ({old: (new, object)})
    with a FutureWarning: ``from module import Old`` keeps working and says what to write."""

    def __getattr__(name: str) -> Any:
        if name in renamed:
            new, obj = renamed[name]
            warn_renamed("name", f"{module}.{name}", new)
            return obj
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    return __getattr__


def renamed_keywords(**renamed: str) -> Callable[[Callable], Callable]:
    """Decorator: keyword ``old=`` of the function (``renamed_keywords(old="new")``) is
    passed on as ``new=``, with a FutureWarning; giving both is a ValueError."""

    def decorate(f: Callable) -> Callable:
        @functools.wraps(f)
        def wrapper(*args, **kwargs):
            for old, new in renamed.items():
                if old in kwargs:
                    if new in kwargs:
                        raise ValueError(f"{f.__qualname__}: pass {new}= only (its old name {old}= was given as well)")
                    warn_renamed(f"{f.__qualname__}() keyword", old, new)
                    kwargs[new] = kwargs.pop(old)
            return f(*args, **kwargs)

        return wrapper

    return decorate


def renamed_key(d: dict[str, Any], old: str, new: str, where: str = "") -> dict[str, Any]:
    """``d`` with its key ``old`` written ``new`` (a FutureWarning when it was ``old``); both
    at once is a ValueError. ``d`` itself is not modified."""
    if old not in d:
        return d
    if new in d:
        raise ValueError(f"{where}dict has both {new!r} and its old name {old!r}; keep {new!r}")
    warn_renamed(f"{where}dict key", old, new, stacklevel=4)
    return {(new if k == old else k): v for k, v in d.items()}
