"""Procedural scenes and scene files for bsdflab's path tracer (the layer above
bsdflab.render, whose ``Scene`` they build).

``scene(name, **options)`` builds a registered scene (``SCENES``); ``save_scene`` /
``load_scene`` read and write scene files (docs/scene_format.md). ``build_mesh`` (a shape's
geometry spec as a triangle mesh) is the renderer's, bsdflab.render.geometry, re-exported.
"""
from bsdflab.render.geometry import GEOMETRY_TYPES, Mesh, build_mesh, mesh_area, validate_mesh
from bsdflab.scenes.registry import SCENE_SETS, SCENES, scene, scene_set
from bsdflab.scenes.scene_file import load_scene, save_scene

__all__ = ["GEOMETRY_TYPES", "Mesh", "SCENE_SETS", "SCENES", "scene_set", "build_mesh", "load_scene", "mesh_area",
           "save_scene", "scene", "validate_mesh"]
