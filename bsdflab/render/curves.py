"""The snake: a sinuous centreline on the ground and the surfaces swept along it.

Both ``snake_body`` and ``snake_head`` take the same parameters (SNAKE_DEFAULTS), so a
body and a head built from one parameter set fit together. Lengths are in scene units
(the snake scene uses centimetres).

Centreline: in a local frame (a along the heading, b to the side), b(a) = A(a) sin(2 pi a /
wavelength + phase), with A growing from 0.6 amplitude at the ends to the full amplitude
mid-body; scaled so its arc length is ``length``; rotated by ``heading_deg`` about +Y
(0: the head points to +X) and centred on ``center`` = [x, z]. s (arc length) runs from
the tail tip (0) to the front end of the body (``length``).

Cross-section: in the vertical plane across the (horizontal) tangent. Half-width r(s);
the top half is an ellipse of half-height 0.92 r, the bottom half a flattened curve of
depth ``flatten`` r whose lowest point touches y = 0, so the body rests on the ground.
The frame (horizontal tangent, +Y) is the rotation-minimising frame of the planar
centreline, so the tube has no twist and the belly always faces down.

Radius profile: the tail tapers over ``tail_length`` to a point (r ~ s at the tip); the
neck narrows smoothly over ``neck_length`` to ``neck_radius``; the body's front end is
closed by a rounded cap, hidden inside the head. The head (length ``head_length``,
half-width ``head_width``) continues straight along the body's end tangent from the start
of that cap: flatter than the body, with a rounded snout and a rounded back end inside the
neck.

uv: u = arc length along the centreline (world units, the head continues the body's),
v = angle around the section / 2 pi, starting and ending on the belly line (v = 0 and 1
are both present: the seam column is duplicated).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.render.mesh import Mesh, Params, grid_indices, normalise, reserve

SNAKE_DEFAULTS = {
    "length": 100.0,
    "radius": 1.8,
    "neck_radius": 1.3,
    "tail_length": 22.0,
    "neck_length": 12.0,
    "flatten": 0.8,
    "amplitude": 10.0,
    "wavelength": 32.0,
    "phase_deg": 0.0,
    "center": [0.0, 0.0],
    "heading_deg": 0.0,
    "head_length": 4.4,
    "head_width": 1.45,
    "segments": 800,
    "sides": 48,
    "head_segments": 96,
}
TOP = 0.92            # top half-height / half-width
BELLY_EXPONENT = 0.55  # < 1 flattens the lower half of the section
HEAD_BACK = 0.8       # the head's rounded back end reaches this many neck radii into the neck
HEAD_SNOUT = 0.55     # fraction of the head length where the snout's taper starts


@dataclass(frozen=True)
class SnakeLayout:
    length: float
    radius: float
    neck_radius: float
    tail_length: float
    neck_length: float
    flatten: float
    head_length: float
    head_width: float
    segments: int
    sides: int
    head_segments: int
    s_dense: np.ndarray     # arc length of the dense centreline samples
    xz_dense: np.ndarray    # (n, 2) their world x, z
    t_dense: np.ndarray     # (n, 2) unit tangents (x, z)

    @property
    def cap(self) -> float:
        """Length of the rounded cap closing the body's front end."""
        return 0.6 * self.neck_radius

    @property
    def neck_end(self) -> float:
        """Arc length where the cap starts and the head is attached."""
        return self.length - self.cap

    def centreline(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World (x, z) points and unit horizontal tangents at arc lengths s."""
        xz = np.stack([np.interp(s, self.s_dense, self.xz_dense[:, k]) for k in (0, 1)], axis=-1)
        t = np.stack([np.interp(s, self.s_dense, self.t_dense[:, k]) for k in (0, 1)], axis=-1)
        return xz, normalise(t)

    def body_radius(self, s: np.ndarray) -> np.ndarray:
        """Half-width along the body, without the front cap."""
        x = np.clip(s / self.tail_length, 0.0, 1.0)
        tail = 2 * x - x * x                    # pointed tip, zero slope where it meets the body
        start = self.neck_end - self.neck_length
        neck = _smoothstep((s - start) / self.neck_length)
        return tail * (self.radius + (self.neck_radius - self.radius) * neck)


def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def layout_of(spec: dict) -> SnakeLayout:
    """The layout of a ``snake_body`` / ``snake_head`` spec (missing parameters default)."""
    return snake_layout(Params("snake_body", {**spec, "type": "snake_body"}, SNAKE_DEFAULTS))


def snake_layout(p) -> SnakeLayout:
    """Check a snake spec's parameters (a ``mesh.Params``) and lay out the centreline."""
    length = p.number("length", positive=True)
    values = {name: p.number(name, positive=True) for name in
              ("radius", "neck_radius", "tail_length", "neck_length", "flatten", "wavelength",
               "head_length", "head_width")}
    amplitude = p.number("amplitude", lo=0.0)
    phase = np.radians(p.number("phase_deg"))
    heading = np.radians(p.number("heading_deg"))
    center = p.vector("center", 2)
    layout_ints = dict(segments=p.integer("segments", 16, 200000), sides=p.integer("sides", 6, 4096),
                       head_segments=p.integer("head_segments", 8, 20000))
    # the body's rows (segments, the front cap) or the head's, each (sides + 1) vertices,
    # plus the dense centreline (16 samples per segment, ~10 doubles each)
    rows = max(layout_ints["segments"] + max(4, layout_ints["sides"] // 4), layout_ints["head_segments"] + 2) + 1
    reserve(p.kind, rows * (layout_ints["sides"] + 1) + 4 * layout_ints["segments"],
            2 * rows * layout_ints["sides"])
    if values["flatten"] > 1.0:
        raise ValueError(f"{p.kind}: flatten must be in (0, 1], got {values['flatten']}")
    cap = 0.6 * values["neck_radius"]
    if values["tail_length"] + values["neck_length"] + cap >= length:
        raise ValueError(f"{p.kind}: tail_length + neck_length + 0.6 neck_radius must be shorter than "
                         f"length ({length})")

    # the centreline's local frame: a along the heading, b to the side
    n_dense = 16 * layout_ints["segments"] + 1
    extent = length
    for _ in range(8):   # arc length grows with the extent almost linearly: fixed point
        a = np.linspace(0.0, extent, n_dense)
        t = a / extent
        wave = 2 * np.pi * a / values["wavelength"] + phase
        env = amplitude * (0.6 + 0.4 * np.sin(np.pi * t))
        db = 0.4 * np.pi * amplitude * np.cos(np.pi * t) / extent * np.sin(wave) \
            + env * (2 * np.pi / values["wavelength"]) * np.cos(wave)
        speed = np.hypot(1.0, db)
        s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(a))])
        extent *= length / s[-1]
    b = env * np.sin(wave)
    local = np.stack([a - 0.5 * extent, b - 0.5 * (b.max() + b.min())], axis=-1)
    tangent = np.stack([np.ones_like(db), db], axis=-1) / speed[:, None]
    # rotation by heading about +Y: +X -> (cos h, -sin h), the side axis +Z -> (sin h, cos h)
    rot = np.array([[np.cos(heading), np.sin(heading)], [-np.sin(heading), np.cos(heading)]])
    shape = {k: v for k, v in values.items() if k != "wavelength"}
    return SnakeLayout(length=length, **shape, **layout_ints, s_dense=s * (length / s[-1]),
                       xz_dense=local @ rot.T + center, t_dense=tangent @ rot.T)


# -- surfaces ----------------------------------------------------------------------------------
def _sweep(xz: np.ndarray, tangent: np.ndarray, u: np.ndarray, width: np.ndarray, top: np.ndarray,
           low: np.ndarray, sides: int) -> Mesh:
    """A closed tube over rows of cross-sections: row k is centred on xz[k] at height
    low[k] (so its lowest point is on y = 0), half-width width[k], half-heights top[k]
    above and low[k] below its centre. The first and last rows must have zero width (the
    tips); their normals point back / forward along the tangent."""
    v = np.linspace(0.0, 1.0, sides + 1)
    psi = -0.5 * np.pi + 2 * np.pi * v           # v = 0 and 1 on the belly line
    c, s = np.cos(psi), np.sin(psi)
    lateral = width[:, None] * c
    vertical = np.where(s >= 0, top[:, None] * s, -low[:, None] * np.abs(s) ** BELLY_EXPONENT)
    side = np.stack([tangent[:, 1], np.zeros(len(u)), -tangent[:, 0]], axis=-1)  # +Y x tangent
    centre = np.stack([xz[:, 0], low, xz[:, 1]], axis=-1)
    pos = centre[:, None, :] + lateral[..., None] * side[:, None, :]
    pos[..., 1] += vertical

    d_row = np.gradient(pos, u, axis=0, edge_order=2)
    ring = pos[:, :-1]                            # without the duplicated seam column
    d_psi = np.roll(ring, -1, axis=1) - np.roll(ring, 1, axis=1)
    n = np.cross(d_psi, d_row[:, :-1])
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    t3 = np.stack([tangent[:, 0], np.zeros(len(u)), tangent[:, 1]], axis=-1)
    tip = np.zeros(len(u))
    tip[0], tip[-1] = -1.0, 1.0
    fallback = np.broadcast_to((tip[:, None] * t3)[:, None, :], n.shape)
    degenerate = length < 1e-12 * max(1.0, float(np.max(width)) ** 2)
    n = np.where(degenerate, fallback, n / np.where(degenerate, 1.0, length))
    n = np.concatenate([n, n[:, :1]], axis=1)
    uv = np.stack(np.broadcast_arrays(u[:, None], v[None, :]), axis=-1)
    rows = len(u) - 1
    indices = grid_indices(rows, sides, flip=True, collapsed_first=True, collapsed_last=True)
    return Mesh(pos.reshape(-1, 3), indices, n.reshape(-1, 3), uv.reshape(-1, 2))


def snake_body(layout: SnakeLayout) -> Mesh:
    s_body = np.linspace(0.0, layout.neck_end, layout.segments + 1)
    n_cap = max(4, layout.sides // 4)
    alpha = np.linspace(0.0, 0.5 * np.pi, n_cap + 1)[1:]
    s = np.concatenate([s_body, layout.neck_end + layout.cap * np.sin(alpha)])
    width = np.concatenate([layout.body_radius(s_body), layout.neck_radius * np.cos(alpha)])
    width[-1] = 0.0
    xz, tangent = layout.centreline(s)
    return _sweep(xz, tangent, s, width, TOP * width, layout.flatten * width, layout.sides)


def _head_profile(layout: SnakeLayout, x: np.ndarray):
    """Half-width, top and bottom half-heights of the head at distance x from the neck end
    (x < 0: the rounded back end inside the neck)."""
    length, neck = layout.head_length, layout.neck_radius
    t = np.clip(x / length, 0.0, 1.0)
    back = np.sqrt(np.clip(1 - (np.minimum(x, 0.0) / (HEAD_BACK * neck)) ** 2, 0.0, 1.0))
    snout = np.sqrt(np.clip(1 - ((t - HEAD_SNOUT) / (1 - HEAD_SNOUT)).clip(0.0, 1.0) ** 2, 0.0, 1.0))
    grow = _smoothstep(t / 0.4)
    width = (0.97 * neck + (layout.head_width - 0.97 * neck) * grow) * back * snout
    flat = _smoothstep((t - 0.1) / 0.5)
    top = (TOP + (0.62 - TOP) * flat) * width
    low = (layout.flatten + (0.5 - layout.flatten) * flat) * width
    return width, top, low


def _head_rows(layout: SnakeLayout) -> np.ndarray:
    """Row positions along the head, dense where the rounded ends curve fast."""
    n = layout.head_segments
    n_end = max(4, n // 4)
    angle = np.linspace(0.0, 0.5 * np.pi, n_end + 1)
    back = -HEAD_BACK * layout.neck_radius * np.cos(angle[:-1])
    snout_start = HEAD_SNOUT * layout.head_length
    middle = np.linspace(0.0, snout_start, max(2, n - 2 * n_end) + 1)[:-1]
    snout = snout_start + (layout.head_length - snout_start) * np.sin(angle)
    return np.concatenate([back, middle, snout])


def _head_frame(layout: SnakeLayout) -> tuple[np.ndarray, np.ndarray]:
    xz, tangent = layout.centreline(np.array([layout.neck_end]))
    return xz[0], tangent[0]


def snake_head(layout: SnakeLayout) -> Mesh:
    x = _head_rows(layout)
    width, top, low = _head_profile(layout, x)
    width[0] = width[-1] = 0.0
    origin, tangent = _head_frame(layout)
    xz = origin + x[:, None] * tangent
    return _sweep(xz, np.tile(tangent, (len(x), 1)), layout.neck_end + x, width, top, low, layout.sides)


def snake_eyes(layout: SnakeLayout, radius_fraction: float = 0.045) -> list[tuple[list[float], float]]:
    """(centre, radius) of the two eyes: small spheres half sunk into the head's upper
    sides, half-way along the head."""
    x = np.array([0.5 * layout.head_length])
    width, top, low = (float(a[0]) for a in _head_profile(layout, x))
    radius = radius_fraction * layout.head_length
    psi = np.radians(35.0)
    origin, tangent = _head_frame(layout)
    side = np.array([tangent[1], 0.0, -tangent[0]])
    t3 = np.array([tangent[0], 0.0, tangent[1]])
    normal = np.array([np.cos(psi) / width, np.sin(psi) / top])
    normal /= np.linalg.norm(normal)
    eyes = []
    for sign in (1.0, -1.0):
        lateral = width * np.cos(psi) - 0.4 * radius * normal[0]
        height = low + top * np.sin(psi) - 0.4 * radius * normal[1]
        centre = np.array([origin[0], 0.0, origin[1]]) + x[0] * t3 + sign * lateral * side
        centre[1] = height
        eyes.append(([float(c) for c in centre], float(radius)))
    return eyes
