"""The fit's forward model: parameter sets -> the observables of a dataset, in the C++ core.

``ForwardModel(dataset)`` compiles the dataset's rows (geometry, angles, wavelengths) once;
``evaluate(theta)`` maps parameter sets (P, 10) -- columns in ``FORWARD_NAMES`` order --
to model values (P, rows), threaded and without the GIL. The physics (film, slab, base,
thickness spread) is documented in core/include/bsdflab/fit_forward.h; the layered part is
restricted to NON-SCATTERING slabs, where it is exact up to quadrature.
"""
from __future__ import annotations

import numpy as np

from bsdflab import _core
from bsdflab.fit.data import GEOMETRIES, SPECULAR_TOLERANCE_DEG, Dataset
from bsdflab.fit.parameters import FORWARD_NAMES, PARAMETERS

THICKNESS_NODES = 24   # Gauss-Hermite nodes over the thickness distribution
ANGLE_NODES = 32       # Gauss-Legendre nodes of the hemispherical integrals


class ForwardModel:
    """Observables of ``dataset``'s rows for parameter sets.

    Parameters
    ----------
    dataset : Dataset
        Only the geometry, angles and wavelengths are used.
    thickness_nodes : int >= 1
        Gauss-Hermite order of the thickness-spread average (exact for a spread of 0).
    angle_nodes : int >= 2
        Gauss-Legendre order of the slab's hemispherical integrals (diffuse, total rows).
    """

    def __init__(self, dataset: Dataset, thickness_nodes: int = THICKNESS_NODES,
                 angle_nodes: int = ANGLE_NODES):
        if not isinstance(thickness_nodes, (int, np.integer)) or not 1 <= thickness_nodes <= 200:
            raise ValueError(f"thickness_nodes must be an integer in [1, 200], got {thickness_nodes!r}")
        if not isinstance(angle_nodes, (int, np.integer)) or not 2 <= angle_nodes <= 1000:
            raise ValueError(f"angle_nodes must be an integer in [2, 1000], got {angle_nodes!r}")
        self.dataset = dataset
        self.thickness_nodes, self.angle_nodes = int(thickness_nodes), int(angle_nodes)
        self.wavelengths, index = np.unique(dataset.wavelength_nm, return_inverse=True)
        brdf = dataset.geometry == GEOMETRIES.index("brdf")
        mirror = brdf & (np.abs(dataset.angle_out_deg - dataset.angle_deg) < SPECULAR_TOLERANCE_DEG) & (
            np.abs(dataset.phi_deg) < SPECULAR_TOLERANCE_DEG)
        if np.any(mirror):
            raise ValueError(f"brdf row {int(np.argmax(mirror))} is at the mirror direction, where the smooth model's "
                             "reflection is a delta (use a specular row, or [model] kind = 'full')")
        # the smooth model's off-specular light depends on the polar angles only: brdf = diffuse
        geometry = np.where(brdf, GEOMETRIES.index("diffuse"), dataset.geometry)
        out = np.where(geometry == GEOMETRIES.index("diffuse"), np.abs(dataset.angle_out_deg), 0.0)
        gh_x, gh_w = np.polynomial.hermite.hermgauss(self.thickness_nodes)
        gl_x, gl_w = np.polynomial.legendre.leggauss(self.angle_nodes)
        self._core = _core.FitForwardModel(
            self.wavelengths, geometry.astype(np.int32), index.astype(np.int32),
            np.cos(np.radians(dataset.angle_deg)), np.cos(np.radians(out)), gh_x, gh_w, gl_x, gl_w)

    @property
    def rows(self) -> int:
        return self._core.rows

    def evaluate(self, theta) -> np.ndarray:
        """Model values (P, rows) for parameter sets ``theta`` (P, 10) or (10,) -> (rows,).
        Sets outside the model's domain give NaN rows."""
        t, single = parameter_sets("theta", theta, FORWARD_NAMES)
        out = self._core.evaluate(np.ascontiguousarray(t))
        return out[0] if single else out


def parameter_sets(label: str, values, names) -> tuple[np.ndarray, bool]:
    """(P, len(names)) float array of parameter sets and whether one set (a 1-D array) was given."""
    t = np.asarray(values, dtype=np.float64)
    single = t.ndim == 1
    t = np.atleast_2d(t)
    if t.shape[-1] != len(names):
        raise ValueError(f"{label} must end in an axis of {len(names)} parameters "
                         f"({', '.join(names)}), got shape {t.shape}")
    return t, single


def default_theta(**overrides) -> np.ndarray:
    """A full parameter vector: the preset defaults, with ``overrides`` by name."""
    values = {p.name: p.default for p in PARAMETERS}
    for k, v in overrides.items():
        if k not in values:
            raise ValueError(f"unknown forward parameter {k!r}; known: {', '.join(FORWARD_NAMES)}")
        values[k] = float(v)
    return np.array([values[n] for n in FORWARD_NAMES])
