"""Blender: a Python script that builds the scene, and the ``.blend`` it makes with ``bpy``.

The script (written beside the .blend, ``<out>.py``, for users who run their own Blender:
``blender --background --python snake.blend.py``) builds a smooth UV sphere with a
Principled BSDF (Base Color = body colour, Roughness = sqrt(GGX alpha), IOR = fitted base
index, Thin Film Thickness (nm) / Thin Film IOR = fitted film), a constant white world
(strength 1), an orthographic camera looking down -y at the sphere, a sun light (off by
default: the constant world is the cross-check's scene) and Cycles on the CPU with a fixed
seed. ``bpy`` runs in a child process so that Blender never shares bsdflab's interpreter,
and in its own environment: bpy 5.0.1 pins numpy < 2, so ``./dev.sh setup`` installs it in
``.venv-blender`` beside ``.venv``; ``BSDFLAB_BLENDER_PYTHON`` names another interpreter
that can ``import bpy``.
"""
from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

from bsdflab.util.settings import library_settings

TIMEOUT_S = 600.0

SCRIPT = '''"""Built by bsdflab export: the material {name!r} in Blender (Principled BSDF with Thin Film)."""
import os
import sys

import bpy

P = {params}
SAVE_AS = {save_as!r}
if "--" in sys.argv and len(sys.argv) > sys.argv.index("--") + 1:
    SAVE_AS = sys.argv[sys.argv.index("--") + 1]

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene

mat = bpy.data.materials.new("bsdflab_material")
mat.use_nodes = True
bsdf = mat.node_tree.nodes["Principled BSDF"]
bsdf.inputs["Base Color"].default_value = (*P["base_color"], 1.0)
bsdf.inputs["Metallic"].default_value = 0.0
bsdf.inputs["Roughness"].default_value = P["roughness"]
bsdf.inputs["IOR"].default_value = P["base_ior"]
bsdf.inputs["Thin Film Thickness"].default_value = P["film_thickness_nm"]
bsdf.inputs["Thin Film IOR"].default_value = P["film_ior"]

bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128, radius=1.0, location=(0.0, 0.0, 0.0))
sphere = bpy.context.active_object
sphere.name = "sphere"
bpy.ops.object.shade_smooth()
sphere.data.materials.append(mat)

world = bpy.data.worlds.new("white")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
scene.world = world

cam = bpy.data.cameras.new("camera")
cam.type = "ORTHO"
cam.ortho_scale = 2.0
cam_obj = bpy.data.objects.new("camera", cam)
cam_obj.location = (0.0, -5.0, 0.0)
cam_obj.rotation_euler = (1.5707963267948966, 0.0, 0.0)
scene.collection.objects.link(cam_obj)
scene.camera = cam_obj

sun = bpy.data.lights.new("sun", type="SUN")
sun.energy = 0.0  # raise it for a lit look; the constant world alone is the validation scene
sun_obj = bpy.data.objects.new("sun", sun)
sun_obj.rotation_euler = (0.6, 0.3, 0.0)
scene.collection.objects.link(sun_obj)

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 64
scene.cycles.seed = 0
scene.cycles.use_denoising = False
scene.cycles.max_bounces = 4
scene.render.resolution_x = scene.render.resolution_y = 256
scene.render.resolution_percentage = 100
scene.render.film_transparent = False
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"

SNAKE = os.environ.get("SNAKE_MESH_NPZ")   # an .npz from bsdflab.export.snake_mesh (set by the parent)
if SNAKE:
    import numpy as np
    from mathutils import Vector

    d = np.load(SNAKE)
    pos, idx = d["positions"], d["indices"]
    mesh = bpy.data.meshes.new("snake")
    mesh.vertices.add(len(pos))
    mesh.vertices.foreach_set("co", pos.astype(np.float32).ravel())
    mesh.loops.add(idx.size)
    mesh.loops.foreach_set("vertex_index", idx.astype(np.int32).ravel())
    mesh.polygons.add(len(idx))
    mesh.polygons.foreach_set("loop_start", np.arange(0, idx.size, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(idx), 3, dtype=np.int32))
    mesh.update()
    mesh.validate()
    mesh.shade_smooth()
    mesh.normals_split_custom_set_from_vertices([tuple(n) for n in d["normals"]])
    mesh.materials.append(mat)
    snake_scene = bpy.data.scenes.new("snake")
    snake_scene.world = world
    snake_obj = bpy.data.objects.new("snake", mesh)
    snake_scene.collection.objects.link(snake_obj)
    snake_cam = bpy.data.cameras.new("snake camera")
    snake_cam.sensor_fit = "HORIZONTAL"
    snake_cam.angle = float(d["fov_x_deg"]) * 3.141592653589793 / 180.0
    snake_cam_obj = bpy.data.objects.new("snake camera", snake_cam)
    snake_cam_obj.location = tuple(d["camera_origin"])
    snake_cam_obj.rotation_euler = (Vector(tuple(d["camera_target"])) - Vector(tuple(d["camera_origin"]))
                                    ).to_track_quat("-Z", "Y").to_euler()
    snake_scene.collection.objects.link(snake_cam_obj)
    snake_scene.camera = snake_cam_obj
    snake_scene.render.engine = "CYCLES"
    snake_scene.cycles.device = "CPU"
    snake_scene.cycles.samples = 64
    snake_scene.cycles.use_denoising = False
    snake_scene.render.resolution_x, snake_scene.render.resolution_y = (int(v) for v in d["size"])
    snake_scene.view_settings.view_transform = "Standard"

if SAVE_AS:
    bpy.context.preferences.filepaths.save_version = 0  # no "<file>.blend1" backup beside it
    bpy.ops.wm.save_as_mainfile(filepath=SAVE_AS, compress=False)
'''

RENDER = '''import sys
import bpy
blend, out, size, spp, seed, threads = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.wm.open_mainfile(filepath=blend)
scene = bpy.context.scene
scene.render.resolution_x = scene.render.resolution_y = int(size)
scene.cycles.samples = int(spp)
scene.cycles.seed = int(seed)
scene.cycles.use_adaptive_sampling = False
scene.render.threads_mode = "FIXED"
scene.render.threads = int(threads)
scene.render.filepath = out
bpy.ops.render.render(write_still=True)
'''


def blender_script(params: dict, name: str = "bsdflab", save_as: str = "") -> str:
    """The Python source that builds the scene (and saves it to ``save_as`` or to the path
    after ``--`` on its command line)."""
    p = {k: params[k] for k in ("base_color", "roughness", "base_ior", "film_thickness_nm", "film_ior")}
    p["base_color"] = [float(x) for x in p["base_color"]]
    return SCRIPT.format(name=name, params=json.dumps(p), save_as=save_as)


def blender_python() -> str:
    """The Python interpreter that runs bpy: ``BSDFLAB_BLENDER_PYTHON``, else the
    ``.venv-blender`` beside this environment or this checkout, else this interpreter if it
    has bpy; ValueError when there is none."""
    named = library_settings().blender_python
    if named:
        if not os.access(named, os.X_OK):
            raise ValueError(f"BSDFLAB_BLENDER_PYTHON={named} is not an executable")
        return named
    for root in (Path(sys.prefix).parent, Path(__file__).resolve().parents[2]):
        candidate = root / ".venv-blender" / "bin" / "python"
        if os.access(candidate, os.X_OK):
            return str(candidate)
    if importlib.util.find_spec("bpy") is not None:
        return sys.executable
    raise ValueError("the blender format needs bpy (Blender as a Python module): run ./dev.sh setup, "
                     "or set BSDFLAB_BLENDER_PYTHON to a Python that has bpy 5.0")


def run_bpy(code: str, args: list[str] = (), timeout: float = TIMEOUT_S, env: dict | None = None) -> str:
    """Run ``code`` under bpy in a child process (``args`` after ``--``); its stdout, or
    RuntimeError with the last lines of its output."""
    proc = subprocess.run([blender_python(), "-c", code, "--", *args], capture_output=True, text=True,
                          timeout=timeout, env=env)
    if proc.returncode != 0:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
        raise RuntimeError(f"bpy failed ({proc.returncode}): {' | '.join(tail)}")
    return proc.stdout


def write_blend(params: dict, path: str, name: str = "bsdflab", snake: bool = True) -> None:
    """Run the script under bpy (a child process) to save the .blend at ``path``; with
    ``snake``, the .blend also holds a scene "snake" (the snake's mesh and camera,
    ``bsdflab.export.snake_mesh``) with the same material."""
    import tempfile

    import numpy as np

    with tempfile.TemporaryDirectory() as tmp:
        env = None
        if snake:
            from bsdflab.export.snake_mesh import snake_mesh

            npz = os.path.join(tmp, "snake.npz")
            np.savez(npz, **snake_mesh())
            env = dict(os.environ, SNAKE_MESH_NPZ=npz)
        run_bpy(blender_script(params, name), [os.path.abspath(path)], env=env)


def render_blend(blend: str, out_exr: str, size: int = 64, spp: int = 16, seed: int = 0, threads: int = 2,
                 timeout: float = TIMEOUT_S) -> None:
    """Render a .blend with Cycles (CPU) into a linear EXR."""
    run_bpy(RENDER, [os.path.abspath(blend), os.path.abspath(out_exr), str(size), str(spp), str(seed),
                      str(threads)], timeout)
