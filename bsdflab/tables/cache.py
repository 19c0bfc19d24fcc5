"""A folder of table files keyed by what was tabulated, so a repeated request is a file read.

``get(request, cache=..., runner=...)`` is the one way a table is asked for (the CLI, jobs,
renders and the service call it with a ``TableRequest``, bsdflab.tables.request). Each
table lives at ``<cache_dir>/<key>.exr`` where the key (``TableRequest.key``) hashes
everything that can change a table's content: the model, the grid, the target relative error, the channels,
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

import logging
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

from bsdflab.bsdfs.base import from_dict
from bsdflab.tables.channels import channel_wavelengths
from bsdflab.tables.data import TableData, TableGrid, check_table_memory
from bsdflab.tables.file_format import canonical_json, read_table, write_table
from bsdflab.tables.request import TableRequest
from bsdflab.tables.tabulate import make_table
from bsdflab.util import args as check
from bsdflab.util.runners import Runner
from bsdflab.util.settings import library_settings

ENV_VAR = "BSDFLAB_CACHE_DIR"
RGB = ("R", "G", "B")

log = logging.getLogger(__name__)


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


def legacy_request(model_dict: dict[str, Any], grid: TableGrid | dict[str, Any], rel_error: float,
                   channels: str | Sequence[Any], min_samples: int | None = None,
                   max_samples: int | None = None, seed: int | None = None,
                   method: str = "pfmc") -> TableRequest:
    """The TableRequest of the positional (model dict, grid, target, channels, ...) form
    (omitted effort and seed: the defaults, so a request that spells them out shares the
    entry of one that does not)."""
    names = channel_names(channels)
    effort = {k: v for k, v in (("min_samples", min_samples), ("max_samples", max_samples), ("seed", seed))
              if v is not None}
    return TableRequest.make(from_dict(model_dict), grid, rel_error, channel_wavelengths(names), method, **effort)


def request_dict(*args, **kwargs) -> dict[str, Any]:
    """Everything that determines a table's content (``TableRequest.content`` of
    ``legacy_request(...)``): a PFMC request has no ``method`` entry, so the keys of tables
    cached before methods existed still match; an adding-doubling request records the
    method and the solver's settings, and no walk effort or seed."""
    return legacy_request(*args, **kwargs).content()


def cache_key(*args, **kwargs) -> str:
    """``TableRequest.key`` of ``legacy_request(...)``: SHA-256 (hex) of the canonical JSON
    of the channels, format version, grid, model, target error, effort, seed, error floor
    and estimator version (for adding-doubling: the method and solver settings)."""
    return legacy_request(*args, **kwargs).key()


def mismatch(table: TableData, request: dict[str, Any]) -> str | None:
    """Why ``table`` is not the table ``request`` (a ``request_dict``) asks for, or None."""
    meta = table.meta
    found = {
        "model": _canonical_model(table.model) == canonical_json(request["model"]),
        "grid": table.grid.to_dict() == request["grid"],
        "rel_error": table.rel_error_target == request["rel_error"],
        "channels": list(table.channels) == request["channels"],
        "method": meta.get("method", "pfmc") == request.get("method", "pfmc"),
    }
    if "method" not in request and table.split_direct:  # stochastic tables record their effort and seed
        found.update({k: meta.get(k) == request[k] for k in ("min_samples", "max_samples", "seed")})
    wrong = [k for k, ok in found.items() if not ok]
    return f"it holds a different {', '.join(wrong)}" if wrong else None


def _canonical_model(d: dict[str, Any]) -> str:
    """A model dict in the form requests key it (``from_dict(d).to_dict()``)."""
    try:
        return canonical_json(from_dict(d).to_dict())
    except ValueError:
        return canonical_json(d)


class Fetched(NamedTuple):
    """A table from ``get``: the table, its cache file (None: not cached) and whether it
    was read from the cache (``make`` not called)."""

    table: TableData
    path: Path | None
    from_cache: bool


def get(request: TableRequest, cache: str | os.PathLike | bool | None = None, runner: Runner | None = None,
        progress: bool = False, make: Callable[[], TableData] | None = None) -> Fetched:
    """The table ``request`` asks for: read from the cache, or tabulated (once) and cached.

    Parameters
    ----------
    request : TableRequest
        What to tabulate and how (bsdflab.tables.request; its ``method`` already resolved).
    cache : folder, None or False
        The cache folder (None: ``cache_dir()``); False: tabulate, neither read nor write.
    runner : bsdflab.util.runners.Runner, optional
        Tabulate on this runner (a Dask cluster; bsdflab.tables.units) instead of this process.
    progress : bool
        A progress bar on stderr while tabulating.
    make : callable, optional
        Builds the table instead of ``make_table(request, ...)`` (it must honour the request;
        e.g. a job's progress reporting around it).

    Check ``table.accuracy()["target_met"]``: a table that misses its target is returned,
    and says so.
    """
    if not isinstance(request, TableRequest):
        raise ValueError(f"request must be a TableRequest, got {type(request).__name__}")
    if make is None:
        def make():
            return make_table(request, progress=progress, runner=runner)
    if cache is False:
        return Fetched(make(), None, False)
    return Fetched(*_cached(request, make, None if cache is True else cache))


def cached_table(model_dict: dict[str, Any], grid: TableGrid | dict[str, Any], rel_error: float,
                 channels: str | Sequence[Any], make: Callable[[], TableData],
                 directory: str | os.PathLike | None = None, min_samples: int | None = None,
                 max_samples: int | None = None, seed: int | None = None, method: str = "pfmc",
                 ) -> tuple[TableData, Path | None, bool]:
    """``get`` in the positional form (``legacy_request``), with the table made by ``make``:
    (table, cache file or None when the folder was not writable, read from the cache)."""
    request = legacy_request(model_dict, grid, rel_error, channels, min_samples, max_samples, seed, method)
    return _cached(request, make, directory)


def _cached(request: TableRequest, make: Callable[[], TableData],
            directory: str | os.PathLike | None) -> tuple[TableData, Path | None, bool]:
    """The cached table for ``request``, tabulating it with ``make()`` only when needed;
    path None when the table was built but the folder was not writable (a warning is
    logged: the table is still returned)."""
    content = request.content()
    check_table_memory(request.grid, len(request.channels))
    path = cache_dir(directory) / f"{request.key()}.exr"
    if path.exists():
        try:
            table = read_table(path)
            why = mismatch(table, content)
            if why is None:
                return table, path, True
            log.warning("cached table %s is not the one requested (%s); rebuilding it", path, why)
        except ValueError as e:
            log.warning("cached table is unusable, rebuilding it: %s", e)
    table = make()
    why = mismatch(table, content)
    if why is not None:
        raise ValueError(f"the table made for this cache request does not match it: {why}")
    try:
        write_table(path, table)
    except OSError as e:
        log.warning("could not write table cache file %s: %s", path, e)
        return table, None, False
    return table, path, False
