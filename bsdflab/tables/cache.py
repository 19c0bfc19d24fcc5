"""A folder of table files keyed by what was tabulated, so a repeated request is a file read.

Each table lives at ``<cache_dir>/<key>.exr`` where the key hashes everything that can
change a table's content: the model, the grid, the target relative error, the channels,
the effort (``min_samples``, ``max_samples``), the seed, the table format version, the
tabulator's error floor and the core's estimator version; for a table by adding-doubling
(``method="adding-doubling"``, deterministic) the method and the solver's settings instead
of the walks' effort, seed and estimator version. A file read back is checked to
be the table that was asked for (its header must repeat the request) before it is
returned. Files are written atomically, so concurrent writers of the same key are safe:
the last rename wins and every reader sees a complete file. A file that fails
verification is logged and rebuilt.
"""
from __future__ import annotations

import hashlib
import inspect
import logging
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from bsdflab import _core
from bsdflab.tables.data import FORMAT_VERSION, TableData, TableGrid, check_table_memory
from bsdflab.tables.file_format import canonical_json, read_table, write_table
from bsdflab.tables.tabulate import ERROR_FLOOR, METHODS, tabulate
from bsdflab.util import args as check
from bsdflab.util.settings import library_settings

ENV_VAR = "BSDFLAB_CACHE_DIR"
RGB = ("R", "G", "B")

log = logging.getLogger(__name__)


def _tabulate_defaults() -> dict[str, Any]:
    params = inspect.signature(tabulate).parameters
    return {name: params[name].default for name in ("min_samples", "max_samples", "seed")}


def estimator_version() -> int:
    """The core's estimator version (changes whenever the same request gives other walks)."""
    return int(getattr(_core, "estimator_version", 1))


def cache_dir(directory: str | os.PathLike | None = None) -> Path:
    """The folder holding cached tables.

    Parameters
    ----------
    directory : str or path-like, optional
        Use this folder. Otherwise ``$BSDFLAB_CACHE_DIR`` when set and non-empty, else
        ``platformdirs.user_cache_dir("bsdflab") / "tables"``. The folder is created when
        the first table is written, not here.
    """
    if directory is not None:
        return Path(directory)
    folder = library_settings().cache_dir   # BSDFLAB_CACHE_DIR
    if folder is not None:
        return folder
    import platformdirs

    return Path(platformdirs.user_cache_dir("bsdflab")) / "tables"


def channel_names(channels: str | Sequence[Any]) -> tuple[str, ...]:
    """Canonical channel names: ``"rgb"`` or ("R", "G", "B") -> RGB; wavelengths -> their
    names as tables store them (``f"{nm:g}"``)."""
    if isinstance(channels, str):
        if channels.lower() != "rgb":
            raise ValueError(f"channels must be 'rgb' or a list of wavelengths, got {channels!r}")
        return RGB
    items = list(channels)
    if [str(c) for c in items] == list(RGB):
        return RGB
    return tuple(f"{w:g}" for w in check.wavelengths_nm("channels", [float(c) for c in items]))


def request_dict(model_dict: dict[str, Any], grid: TableGrid | dict[str, Any], rel_error: float,
                 channels: str | Sequence[Any], min_samples: int | None = None,
                 max_samples: int | None = None, seed: int | None = None,
                 method: str = "pfmc") -> dict[str, Any]:
    """Everything that determines a table's content, with defaults resolved (the key's input).

    A PFMC request has no ``method`` entry, so the keys of tables cached before methods
    existed still match; an adding-doubling request records the method and the solver's
    settings, and no walk effort or seed (they do not apply to it)."""
    defaults = _tabulate_defaults()
    grid_obj = grid if isinstance(grid, TableGrid) else TableGrid.from_dict(dict(grid))
    common = {
        "channels": list(channel_names(channels)),
        "format_version": FORMAT_VERSION,
        "grid": grid_obj.to_dict(),
        "model": model_dict,
        "rel_error": check.real_scalar("rel_error", rel_error, 0.0, 1.0, lo_open=True),
    }
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {check.brief(method)}")
    if method != "pfmc":
        from bsdflab.tables.adding_doubling import solver_settings

        return {**common, "method": method, "solver": solver_settings()}
    return {
        **common,
        "min_samples": check.count("min_samples", defaults["min_samples"] if min_samples is None else min_samples),
        "max_samples": check.count("max_samples", defaults["max_samples"] if max_samples is None else max_samples),
        "seed": check.seed(defaults["seed"] if seed is None else seed),
        "error_floor": ERROR_FLOOR,
        "estimator_version": estimator_version(),
    }


def cache_key(model_dict: dict[str, Any], grid: TableGrid | dict[str, Any], rel_error: float,
              channels: str | Sequence[Any], min_samples: int | None = None,
              max_samples: int | None = None, seed: int | None = None, method: str = "pfmc") -> str:
    """SHA-256 (hex) of the canonical JSON (sorted keys) of ``request_dict(...)``: the
    channels, format version, grid, model, target error, effort, seed, error floor and
    estimator version (for adding-doubling: the method and solver settings). Omitted effort
    and seed take ``tabulate``'s defaults, so a request that spells them out shares the
    entry of one that does not."""
    request = request_dict(model_dict, grid, rel_error, channels, min_samples, max_samples, seed, method)
    try:
        text = canonical_json(request)
    except (TypeError, ValueError) as e:
        raise ValueError(f"cannot build a cache key: {e}") from None
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def mismatch(table: TableData, request: dict[str, Any]) -> str | None:
    """Why ``table`` is not the table ``request`` (a ``request_dict``) asks for, or None."""
    meta = table.meta
    found = {
        "model": canonical_json(table.model) == canonical_json(request["model"]),
        "grid": table.grid.to_dict() == request["grid"],
        "rel_error": table.rel_error_target == request["rel_error"],
        "channels": list(table.channels) == request["channels"],
        "method": meta.get("method", "pfmc") == request.get("method", "pfmc"),
    }
    if "method" not in request and table.split_direct:  # stochastic tables record their effort and seed
        found.update({k: meta.get(k) == request[k] for k in ("min_samples", "max_samples", "seed")})
    wrong = [k for k, ok in found.items() if not ok]
    return f"it holds a different {', '.join(wrong)}" if wrong else None


def cached_table(model_dict: dict[str, Any], grid: TableGrid | dict[str, Any], rel_error: float,
                 channels: str | Sequence[Any], make: Callable[[], TableData],
                 directory: str | os.PathLike | None = None, min_samples: int | None = None,
                 max_samples: int | None = None, seed: int | None = None, method: str = "pfmc",
                 ) -> tuple[TableData, Path | None, bool]:
    """The cached table for this request, tabulating it with `make()` only when needed.

    Parameters
    ----------
    model_dict, grid, rel_error, channels, min_samples, max_samples, seed, method
        What the table holds and how it was measured; together they form the key
        (`cache_key`). `make` must build the table with these same settings.
    make : callable
        Builds the table when there is no valid cached file.
    directory : str or path-like, optional
        Cache folder (default `cache_dir()`).

    Returns
    -------
    table : TableData
        Check ``table.accuracy()["target_met"]``: a table whose cells hit ``max_samples``
        before reaching the target is returned, but says so.
    path : Path or None
        The cache file; None when the table was built but the folder was not writable
        (a warning is logged: the table is still returned).
    hit : bool
        True when the table was read from the cache and `make` was not called.
    """
    request = request_dict(model_dict, grid, rel_error, channels, min_samples, max_samples, seed, method)
    check_table_memory(TableGrid.from_dict(request["grid"]), len(request["channels"]))
    key = cache_key(model_dict, grid, rel_error, channels, min_samples, max_samples, seed, method)
    path = cache_dir(directory) / f"{key}.exr"
    if path.exists():
        try:
            table = read_table(path)
            why = mismatch(table, request)
            if why is None:
                return table, path, True
            log.warning("cached table %s is not the one requested (%s); rebuilding it", path, why)
        except ValueError as e:
            log.warning("cached table is unusable, rebuilding it: %s", e)
    table = make()
    why = mismatch(table, request)
    if why is not None:
        raise ValueError(f"the table made for this cache request does not match it: {why}")
    try:
        write_table(path, table)
    except OSError as e:
        log.warning("could not write table cache file %s: %s", path, e)
        return table, None, False
    return table, path, False
