"""A render request checked at submission as far as its worker would check it: the scene's
materials are valid models and its shapes fit the caps, so a bad option is a 422 now, not
a failed job later (a reflectance of -1, 10^9 subdivisions). Meshes are sized, not built:
building one in the web process cost up to 1.4 s and 612 MB per request."""
from __future__ import annotations

from typing import Any

from bsdflab.bsdfs.base import from_dict
from bsdflab.jobs.render import build_scene
from bsdflab.render.build import TABULATED
from bsdflab.render.geometry import mesh_size


def _model(d: dict[str, Any]) -> None:
    from_dict(d["model"] if d.get("type") == TABULATED else d)   # a table's model, not the table


def check(request: dict[str, Any]) -> None:
    """ValueError naming the problem when the normalised render ``request`` would fail."""
    scene = build_scene(request)
    for material in scene.materials.values():
        for d in (material.bsdf, material.gap_bsdf):
            if d is not None:
                _model(d)
    for shape in scene.shapes:
        mesh_size(shape.geometry)   # parameters and size checked, nothing built: the worker builds
