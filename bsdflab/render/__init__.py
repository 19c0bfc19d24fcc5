"""The path tracer's Python side: scene descriptions, the render driver, image files."""
from bsdflab.render.image_io import read_exr, tone_map, write_exr, write_png
from bsdflab.render.render import RenderResult, render
from bsdflab.render.scene import Camera, Environment, Material, Scene, Shape

__all__ = ["Camera", "Environment", "Material", "RenderResult", "Scene", "Shape", "read_exr", "render",
           "tone_map", "write_exr", "write_png"]
