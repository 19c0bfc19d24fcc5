"""A render request checked at submission as far as its worker would check it: the scene's
materials are valid models (a tabulated one also a valid table request) and its shapes fit
the caps, so a bad option is a 422 now, not a failed job later (a reflectance of -1, 10^9
subdivisions). Meshes are sized, not built: building one in the web process cost up to
1.4 s and 612 MB per request. Stored files (tables, measured files) were found in the store
(and among the client's own uploads) when their hash was resolved; a material that names
one is checked with the file loaded by ``check_stored`` in a check worker process
(bsdflab.service.offload), not here: an RGB RGL file as a tabulated material, a layered
model over a measured base with a bad interface, adding-doubling of a measured file were
failed jobs, now 422s naming ``options.material``."""
from __future__ import annotations

from typing import Any

from bsdflab.bsdfs.base import from_dict
from bsdflab.jobs.render import build_scene
from bsdflab.render.build import TABULATED, table_request
from bsdflab.render.geometry import mesh_size
from bsdflab.tables.channels import table_channels
from bsdflab.tables.data import TableGrid

STORED = ("table", "measured", "merl")   # checked by the store (bsdflab.service.artefact_refs)
OWN = ("object", "skin", "head")          # the scenes' materials a dict options.material replaces


def names_stored(value: Any) -> bool:
    """Whether a model dict names a stored file anywhere (building it would load the file)."""
    if isinstance(value, dict):
        return value.get("type") in STORED or any(names_stored(v) for v in value.values())
    if isinstance(value, list):
        return any(names_stored(v) for v in value)
    return False


def _model(d: dict[str, Any]) -> int:
    """The model checked; the cells of its table (both lobes; 0 when it is not tabulated)."""
    tabulated = d.get("type") == TABULATED
    if not names_stored(d):   # a stored file is not loaded here
        if tabulated:
            table_request(d)   # as the worker asks: the model, the grid, the target, the method
        else:
            from_dict(d)
    if not tabulated:
        return 0
    grid = d.get("grid")
    if not isinstance(grid, dict):
        raise ValueError("grid must be a dict with n_theta_i, n_theta_o, n_phi, thickness_nm")
    g = TableGrid.from_dict(grid)
    return 2 * max(1, len(g.thickness_nm)) * g.n_theta_i * g.n_theta_o * g.n_phi


def check(request: dict[str, Any]) -> tuple[int, list[tuple[str, dict[str, Any]]]]:
    """ValueError naming the problem when the normalised render ``request`` would fail;
    else the cells of the largest table its materials need (for BSDFLAB_LIMIT_TABLE_CELLS)
    and the materials that name stored files, as (where, BSDF dict), for ``check_stored``."""
    cells, stored = 0, []
    scene = build_scene(request)
    own = isinstance(request["options"].get("material"), dict)
    for name, material in scene.materials.items():
        where = "options.material" if own and name in OWN else f"material {name!r}"
        for d in (material.bsdf, material.gap_bsdf):
            if d is not None:
                try:
                    cells = max(cells, _model(d))
                except ValueError as e:
                    raise ValueError(f"{where}: {e}") from None
                if names_stored(d) and (where, d) not in stored:
                    stored.append((where, d))
    for shape in scene.shapes:
        mesh_size(shape.geometry)   # parameters and size checked, nothing built: the worker builds
    return cells, stored


def check_stored(where: str, d: dict[str, Any]) -> None:
    """What the render job asks of a material that names stored files, with the files
    loaded (in a check worker): the model built, and for a tabulated one its table request
    (an RGB render's, as bsdflab.jobs.render.scene_tables asks) and the model's core at the
    table's channels (an RGB RGL file has no spectra to tabulate). ValueError naming ``where``."""
    try:
        if d.get("type") == TABULATED:
            request = table_request(d)
            request.model._core(table_channels(request.wavelengths)[1])
        else:
            from_dict(d).render_core()
    except (ValueError, TypeError, OverflowError) as e:
        raise ValueError(f"{where}: {e}") from None


def check_materials(materials: list) -> dict[str, Any]:
    """``check_stored`` of each (where, BSDF dict); how many were checked."""
    for where, d in materials:
        check_stored(where, d)
    return {"materials": len(materials)}
