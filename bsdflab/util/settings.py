"""One settings model for every ``BSDFLAB_*`` environment variable (docs/settings.md).

`LibrarySettings` holds what the Python API, the CLI and the core read: resource caps
(``BSDFLAB_MAX_*``, bsdflab.util.limits), the table cache folder, the table signing key, the
Mitsuba variant of the cross-checks and the core's thread count. The HTTP service's
settings (``bsdflab.service.settings.Settings``) extend this model with the server's own
fields, so one class lists every variable and one table in the docs describes them.

Settings are read when `library_settings()` is called, not at import: a test or a server
that changes the environment sees the change at the next call.
"""
from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Annotated

from pydantic import BeforeValidator, Field, SecretStr, ValidationError, ValidationInfo
from pydantic_settings import BaseSettings, SettingsConfigDict

GIB = 1 << 30
PREFIX = "BSDFLAB_"
_SUFFIX = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


def variable(field: str) -> str:
    """The environment variable of settings field ``field``."""
    return PREFIX + field.upper()


def hand_down(field: str, value) -> None:
    """Set field ``field``'s variable in this process's environment, so the processes it
    starts next (a server's job workers) and the library's settings read ``value``: how a
    command-line option (``bsdflab serve --cache-dir``) reaches them."""
    os.environ[variable(field)] = str(value)


def _size(value, info: ValidationInfo):
    """Integers, with ``_`` separators or a binary suffix (``512M``, ``8G``); >= 1."""
    if isinstance(value, int) and not isinstance(value, bool):
        number = value
    else:
        text = str(value).strip()
        m = re.fullmatch(r"([0-9][0-9_]*)\s*([KMGT]?)(?:i?B)?", text, flags=re.IGNORECASE)
        if not m:
            raise ValueError(f"environment variable {variable(info.field_name)} must be a positive integer "
                             f"(optionally with K/M/G/T), got {text!r}")
        number = int(m.group(1).replace("_", "")) * _SUFFIX[m.group(2).upper()]
    if number < 1:
        raise ValueError(f"environment variable {variable(info.field_name)} must be >= 1, got {value!r}")
    return number


Size = Annotated[int, BeforeValidator(_size)]


class LibrarySettings(BaseSettings):
    """The library's settings; each field is the variable ``BSDFLAB_<FIELD>``."""

    model_config = SettingsConfigDict(env_prefix=PREFIX, extra="ignore", env_ignore_empty=True)

    max_bytes: Size = Field(4 * GIB, description="estimated peak memory of one request (table, meshes, "
                                                 "render buffers), bytes")
    max_pixels: Size = Field(1 << 26, description="width x height of one render")
    max_triangles: Size = Field(1 << 25, description="triangles of one scene (all shapes together)")
    max_table_cells: Size = Field(1 << 26, description="cells (lobes x thicknesses x theta_i x theta_o x phi) "
                                                       "of one table")
    max_spp: Size = Field(1 << 20, description="samples per pixel of one render")
    threads: int | None = Field(None, ge=1, description="threads of the C++ core (read by the core itself when "
                                                        "it loads; default: all cores)")
    cache_dir: Path | None = Field(None, description="the table cache folder, one for the CLI, the Python API and "
                                                   "bsdflab serve's table and render jobs (serve --cache-dir; "
                                                   "default: the user cache)")
    table_key: SecretStr | None = Field(None, description="key that signs and verifies table files "
                                                          "(bsdflab.tables.signing)")
    mitsuba_variant: str | None = Field(None, description="force the Mitsuba variant of the cross-checks "
                                                          "(scalar_rgb or llvm_ad_rgb)")
    blender_python: str | None = Field(None, description="the Python interpreter with bpy that `bsdflab export "
                                                         "--format blender` runs (default: .venv-blender)")
    connect_timeout_s: float = Field(10.0, gt=0, description="seconds to wait for a Dask scheduler (--scheduler, "
                                                             "dask:<address>) before giving up, before any work")


def library_settings() -> LibrarySettings:
    """The settings as the environment says now; ValueError naming the variable when one
    is malformed."""
    try:
        return LibrarySettings()
    except ValidationError as e:
        error = e.errors()[0]
        cause = error.get("ctx", {}).get("error")
        if cause is not None:
            raise ValueError(str(cause)) from None
        raise ValueError(f"environment variable {variable(str(error['loc'][0]))}: {error['msg']}") from None
