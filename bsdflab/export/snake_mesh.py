"""The snake's mesh and camera in Blender's frame, for the .blend's "snake" scene.

bsdflab's scenes are y-up in centimetres; Blender is z-up: (x, y, z) -> (x, -z, y), and
centimetres become metres (1/100) so the default Cycles settings see a 1 m animal. The
mesh is the snake scene's body and head (``bsdflab.scenes.snake``, no scale texture: the
export has one film thickness) with its vertex normals; the camera is the scene's (a
horizontal field of view, as bsdflab's).
"""
from __future__ import annotations

import numpy as np

CM_TO_M = 0.01


def to_blender(p: np.ndarray) -> np.ndarray:
    p = np.asarray(p, float)
    return np.stack([p[..., 0], -p[..., 2], p[..., 1]], axis=-1)


def snake_mesh(width: int = 640, height: int = 360, y_up: bool = False) -> dict:
    """positions (V, 3) m, indices (T, 3), normals (V, 3), and the camera (origin, target in
    m, fov_x in degrees, width, height), in Blender's frame (``y_up``: in bsdflab's and
    glTF's, y up, still in metres)."""
    from bsdflab.render.geometry import build_mesh
    from bsdflab.scenes.snake import snake

    frame = (lambda p: np.asarray(p, float)) if y_up else to_blender
    scene = snake(width, height, material="xenopeltis-diffuse", scales=False, eyes=False)
    parts = [build_mesh(s.geometry) for s in scene.shapes if s.name in ("body", "head")]
    offsets = np.cumsum([0] + [len(m.positions) for m in parts[:-1]])
    c = scene.camera
    return {"positions": frame(np.concatenate([m.positions for m in parts])) * CM_TO_M,
            "indices": np.concatenate([m.indices + o for m, o in zip(parts, offsets)]).astype(np.int64),
            "normals": frame(np.concatenate([m.normals for m in parts])),
            "camera_origin": frame(c.origin) * CM_TO_M, "camera_target": frame(c.target) * CM_TO_M,
            "fov_x_deg": np.array(c.fov_deg), "size": np.array([c.width, c.height])}
