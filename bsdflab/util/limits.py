"""Resource caps: every large allocation is estimated from the request and refused before
it is made when the estimate exceeds a cap. One module, so the CLI, the Python API and the
HTTP service refuse the same requests with the same message (docs/limits.md).

Each cap is a field of the one settings model (bsdflab.util.settings, docs/settings.md),
read at call time (so a service or a test can tighten it without re-importing):
``BSDFLAB_MAX_BYTES`` (4 GiB of estimated peak memory per request), ``BSDFLAB_MAX_PIXELS``
(2**26), ``BSDFLAB_MAX_TRIANGLES`` (2**25), ``BSDFLAB_MAX_TABLE_CELLS`` (2**26) and
``BSDFLAB_MAX_SPP`` (2**20). Values may be written as integers, with ``_`` separators, or
with a binary suffix (``512M``, ``8G``); a bad value is itself a ``ValueError`` naming the
variable. The HTTP service's per-request limits (``BSDFLAB_LIMIT_*``) sit below these.
The estimates below are deliberately generous (they include the Python-side copies), so a
request that passes its cap fits in about that much memory.
"""
from __future__ import annotations

from dataclasses import dataclass

from bsdflab.util.settings import GIB, LibrarySettings, library_settings, variable

CAPS = ("max_bytes", "max_pixels", "max_triangles", "max_table_cells", "max_spp")
# the defaults by variable name (what callers quote as "the default")
DEFAULTS = {variable(name): LibrarySettings.model_fields[name].default for name in CAPS}

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
    """The cap held in variable ``name`` (a DEFAULTS key), as set now."""
    if name not in DEFAULTS:
        raise KeyError(f"{name} is not one of the caps {', '.join(DEFAULTS)}")
    return getattr(library_settings(), name[len("BSDFLAB_"):].lower())


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
    settings = library_settings()
    return Limits(*(getattr(settings, name) for name in CAPS))


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
