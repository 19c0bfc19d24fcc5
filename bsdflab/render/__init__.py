"""The path tracer's Python side: scene descriptions (``scene.py``), meshes from geometry
specs (``geometry.py``, ``mesh.py``, ``curves.py``), lights without geometry (``lights.py``,
the sun's sky in ``sky.py``), the build into the C++ scene
(``build.py``), the render driver (``render.py``), its work units for runners
(``units.py``), the result (``result.py``) and image files (``image_io.py``)."""
from bsdflab.render.image_io import read_exr, tone_map, write_exr, write_png
from bsdflab.render.lights import Light
from bsdflab.render.render import render
from bsdflab.render.result import RenderResult
from bsdflab.render.scene import Camera, Environment, Material, Scene, Shape

__all__ = ["Camera", "Environment", "Light", "Material", "RenderResult", "Scene", "Shape", "read_exr", "render",
           "tone_map", "write_exr", "write_png"]
