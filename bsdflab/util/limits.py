"""Resource caps: every large allocation is estimated from the request and refused before
it is made when the estimate exceeds a cap. One module, so the CLI, the Python API and the
HTTP service refuse the same requests with the same message (docs/limits.md).

Each cap has a default and an environment override read at call time (so a service or a
test can tighten it without re-importing):

=========================  ==========  =========================================================
variable                   default     what it bounds
=========================  ==========  =========================================================
``BSDFLAB_MAX_BYTES``      4 GiB       estimated peak memory of one request (table, meshes,
                                       render buffers), in bytes
``BSDFLAB_MAX_PIXELS``     2**26       width x height of one render
``BSDFLAB_MAX_TRIANGLES``  2**25       triangles of one scene (all shapes together)
``BSDFLAB_MAX_TABLE_CELLS`` 2**26      cells (lobes x thicknesses x theta_i x theta_o x phi)
                                       of one table
``BSDFLAB_MAX_SPP``        2**20       samples per pixel of one render
=========================  ==========  =========================================================

Values may be written as integers, with ``_`` separators, or with a binary suffix
(``512M``, ``8G``). A bad value is itself a ``ValueError`` naming the variable.
The estimates below are deliberately generous (they include the Python-side copies), so a
request that passes its cap fits in about that much memory.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass

GIB = 1 << 30
DEFAULTS = {
    "BSDFLAB_MAX_BYTES": 4 * GIB,
    "BSDFLAB_MAX_PIXELS": 1 << 26,
    "BSDFLAB_MAX_TRIANGLES": 1 << 25,
    "BSDFLAB_MAX_TABLE_CELLS": 1 << 26,
    "BSDFLAB_MAX_SPP": 1 << 20,
}
_SUFFIX = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}

# Bytes per unit of work, counted from the code that allocates (see docs/limits.md):
# render: 4 double accumulators x 3 channels in the core (96) + mean and variance handed to
# Python (48) + tone-mapping copies (~56).
RENDER_BYTES_PER_PIXEL = 200
# table: the core's value/error doubles per channel (16 C) + luminance and count (20); the
# float32 arrays, EXR images and the table BSDF's copy in Python (~80 C).
TABLE_BYTES_PER_CELL_BASE = 32
TABLE_BYTES_PER_CELL_CHANNEL = 96
# meshes: float64 positions, normals, uvs and their construction temporaries (~200 per
# vertex); int64 + uint32 indices, their construction temporaries and the BVH (~256 per
# triangle).
MESH_BYTES_PER_VERTEX = 256
MESH_BYTES_PER_TRIANGLE = 256
# what a mesh keeps in the core while rendering: float32 positions and normals, uint32
# indices and Embree's BVH (~64 per triangle), per triangle with ~0.5 vertex each.
SCENE_BYTES_PER_TRIANGLE = 128
# a mesh file: what it decodes to relative to its size on disk (binary PLY ~ 12-13 bytes
# per vertex / face becomes float64 / int64 arrays plus trimesh's caches).
MESH_FILE_EXPANSION = 24


def _read(name: str) -> int:
    text = os.environ.get(name, "").strip()
    if not text:
        return DEFAULTS[name]
    m = re.fullmatch(r"([0-9][0-9_]*)\s*([KMGT]?)(?:i?B)?", text, flags=re.IGNORECASE)
    if not m:
        raise ValueError(f"environment variable {name} must be a positive integer "
                         f"(optionally with K/M/G/T), got {text!r}")
    value = int(m.group(1).replace("_", "")) * _SUFFIX[m.group(2).upper()]
    if value < 1:
        raise ValueError(f"environment variable {name} must be >= 1, got {text!r}")
    return value


@dataclass(frozen=True)
class Limits:
    """The caps in force (``current()``)."""

    max_bytes: int
    max_pixels: int
    max_triangles: int
    max_table_cells: int
    max_spp: int


def current() -> Limits:
    """The caps as set now (defaults overridden by the environment)."""
    return Limits(*(_read(name) for name in DEFAULTS))


def _size(n: float) -> str:
    for unit, scale in (("GiB", GIB), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} bytes"


def check_bytes(what: str, estimate: float) -> None:
    """Refuse ``what`` when its estimated memory exceeds ``BSDFLAB_MAX_BYTES``."""
    cap = current().max_bytes
    if estimate > cap:
        raise ValueError(f"{what} would need about {_size(estimate)} of memory, more than the "
                         f"cap of {_size(cap)} (raise it with BSDFLAB_MAX_BYTES)")


def check_count(what: str, count: int, variable: str) -> None:
    """Refuse a count above the cap held in environment ``variable`` (a DEFAULTS key)."""
    cap = _read(variable)
    if count > cap:
        raise ValueError(f"{what} is {count}, more than the cap of {cap} (raise it with {variable})")


def render_bytes(width: int, height: int) -> int:
    return RENDER_BYTES_PER_PIXEL * int(width) * int(height)


def table_bytes(cells: int, channels: int) -> int:
    return int(cells) * (TABLE_BYTES_PER_CELL_BASE + TABLE_BYTES_PER_CELL_CHANNEL * int(channels))


def mesh_bytes(vertices: int, triangles: int) -> int:
    return MESH_BYTES_PER_VERTEX * int(vertices) + MESH_BYTES_PER_TRIANGLE * int(triangles)
