"""Scene files: a scene's dict form as JSON with a format header.

    {"format": "bsdflab-scene", "version": 1, "name": ..., "camera": {...}, "shapes": [...],
     "materials": {...}, "environment": {...}, "max_depth": 8, "rr_depth": 5}

Relative paths in a file (``mesh`` geometry, an envmap environment) are relative to the
file's folder; ``load_scene`` makes them absolute. See docs/scene_format.md.
"""
from __future__ import annotations

import json
import os
from dataclasses import replace

from bsdflab.render import Scene
from bsdflab.render.geometry import GEOMETRY_TYPES
from bsdflab.util import args as check
from bsdflab.util.files import write_atomically

FORMAT = "bsdflab-scene"
VERSION = 1
MAX_FILE_BYTES = 64 << 20  # a scene is a few KiB; meshes live in their own files


def save_scene(scene: Scene, path: str | os.PathLike) -> str:
    """Write ``scene`` to ``path`` (atomically) and return the path."""
    if not isinstance(scene, Scene):
        raise ValueError(f"expected a Scene, got {type(scene).__name__}")
    text = json.dumps({"format": FORMAT, "version": VERSION, **scene.to_dict()}, indent=1, allow_nan=False)

    def write(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text + "\n")

    write_atomically(path, write)
    return os.fspath(path)


def _no_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows (write a finite number)")


def _absolute(path: str, folder: str) -> str:
    return path if os.path.isabs(path) else os.path.normpath(os.path.join(folder, path))


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and validate a scene file; ValueError (naming the file) when it cannot be used."""
    path = os.fspath(path)
    try:
        if os.path.isdir(path):
            raise ValueError(f"scene file {path} is a folder")
        size = os.path.getsize(path)
        if size > MAX_FILE_BYTES:
            raise ValueError(f"scene file {path} is {size} bytes, more than the {MAX_FILE_BYTES} a "
                             "scene file may have (meshes belong in mesh files)")
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise ValueError(f"cannot read scene file {path}: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise ValueError(f"cannot read scene file {path}: not UTF-8 text (byte {e.start})") from None
    try:
        d = json.loads(text, parse_constant=_no_constant)
    except json.JSONDecodeError as e:
        raise ValueError(f"{path}: not valid JSON at line {e.lineno}, column {e.colno}: {e.msg}") from None
    except RecursionError:
        raise ValueError(f"{path}: the JSON is nested too deeply") from None
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from None
    try:
        check.nesting("the scene", d)
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from None
    if not isinstance(d, dict) or d.get("format") != FORMAT:
        found = d.get("format") if isinstance(d, dict) else type(d).__name__
        raise ValueError(f"{path} is not a bsdflab scene file (format {found!r}, expected {FORMAT!r})")
    if d.get("version") != VERSION:
        raise ValueError(f"{path}: unsupported scene file version {d.get('version')!r} (this bsdflab reads {VERSION})")
    body = {k: v for k, v in d.items() if k not in ("format", "version")}
    try:
        scene = Scene.from_dict(body)
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from None
    for shape in scene.shapes:
        if shape.geometry["type"] not in GEOMETRY_TYPES:
            raise ValueError(f"{path}: shape {shape.name!r} has unknown geometry type "
                             f"{shape.geometry['type']!r}; known: {', '.join(GEOMETRY_TYPES)}")
    return _resolve_paths(scene, os.path.dirname(os.path.abspath(path)))


def _resolve_paths(scene: Scene, folder: str) -> Scene:
    shapes = []
    for shape in scene.shapes:
        g = shape.geometry
        if g["type"] == "mesh" and isinstance(g.get("path"), str) and g["path"]:
            shape = replace(shape, geometry={**g, "path": _absolute(g["path"], folder)})
        shapes.append(shape)
    env = scene.environment
    if env.path:
        env = replace(env, path=_absolute(env.path, folder))
    return replace(scene, shapes=tuple(shapes), environment=env)
