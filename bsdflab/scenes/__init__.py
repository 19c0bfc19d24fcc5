"""Geometry builders, procedural scenes and scene files for bsdflab's path tracer.

``scene(name, **options)`` builds a registered scene (``SCENES``); ``build_mesh`` turns a
shape's geometry spec into a triangle mesh; ``save_scene`` / ``load_scene`` read and write
scene files (docs/scene_format.md).
"""
from bsdflab.scenes.geometry import GEOMETRY_TYPES, Mesh, build_mesh, mesh_area, validate_mesh
from bsdflab.scenes.registry import SCENE_SETS, SCENES, scene, scene_set
from bsdflab.scenes.scene_file import load_scene, save_scene

__all__ = ["GEOMETRY_TYPES", "Mesh", "SCENE_SETS", "SCENES", "scene_set", "build_mesh", "load_scene", "mesh_area", "save_scene", "scene",
           "validate_mesh"]
