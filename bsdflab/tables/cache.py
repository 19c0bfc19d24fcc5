"""A folder of table files keyed by what was tabulated, so a repeated request is a file read.

Each table lives at ``<cache_dir>/<key>.exr`` where the key hashes the model, the grid, the
target relative error, the channels and the table format version. Files are written
atomically, so concurrent writers of the same key are safe: the last rename wins and every
reader sees a complete file. A file that fails verification is logged and rebuilt.
"""
from __future__ import annotations

import hashlib
import logging
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from .data import FORMAT_VERSION, TableData, TableGrid
from .file_format import canonical_json, read_table, write_table

ENV_VAR = "BSDFLAB_CACHE_DIR"

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
    if os.environ.get(ENV_VAR):
        return Path(os.environ[ENV_VAR])
    import platformdirs

    return Path(platformdirs.user_cache_dir("bsdflab")) / "tables"


def cache_key(model_dict: dict[str, Any], grid: TableGrid | dict[str, Any], rel_error: float,
              channels: Sequence[str], min_samples: int | None = None) -> str:
    """SHA-256 (hex) of the canonical JSON (sorted keys) of what determines a table.

    Hashed: ``{"channels": [...], "format_version": FORMAT_VERSION, "grid": grid.to_dict(),
    "model": model_dict, "rel_error": float(rel_error)}``, plus ``"min_samples"`` when given
    (a non-default first-pass effort makes a different table).
    """
    grid_dict = grid.to_dict() if isinstance(grid, TableGrid) else dict(grid)
    request = {"channels": [str(c) for c in channels], "format_version": FORMAT_VERSION,
               "grid": grid_dict, "model": model_dict, "rel_error": float(rel_error)}
    if min_samples is not None:
        request["min_samples"] = int(min_samples)
    try:
        text = canonical_json(request)
    except (TypeError, ValueError) as e:
        raise ValueError(f"cannot build a cache key: {e}") from None
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def cached_table(model_dict: dict[str, Any], grid: TableGrid | dict[str, Any], rel_error: float,
                 channels: Sequence[str], make: Callable[[], TableData],
                 directory: str | os.PathLike | None = None,
                 min_samples: int | None = None) -> tuple[TableData, Path | None, bool]:
    """The cached table for this request, tabulating it with `make()` only when needed.

    Parameters
    ----------
    model_dict, grid, rel_error, channels
        What the table holds; together they form the key (`cache_key`).
    make : callable
        Builds the table when there is no valid cached file.
    directory : str or path-like, optional
        Cache folder (default `cache_dir()`).

    Returns
    -------
    table : TableData
    path : Path or None
        The cache file; None when the table was built but the folder was not writable
        (a warning is logged: the table is still returned).
    hit : bool
        True when the table was read from the cache and `make` was not called.
    """
    path = cache_dir(directory) / f"{cache_key(model_dict, grid, rel_error, channels, min_samples)}.exr"
    if path.exists():
        try:
            return read_table(path), path, True
        except ValueError as e:
            log.warning("cached table is unusable, rebuilding it: %s", e)
    table = make()
    try:
        write_table(path, table)
    except OSError as e:
        log.warning("could not write table cache file %s: %s", path, e)
        return table, None, False
    return table, path, False
