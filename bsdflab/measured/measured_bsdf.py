"""``Measured``: an RGL ``.bsdf`` material (Dupuy & Jakob 2018) as a bsdflab BSDF.

Reflection only, one-sided (zero when either direction is below the surface), one glossy
lobe -- as Mitsuba 3's ``measured`` plugin. Evaluated by the C++ core
(core/include/bsdflab/measured.h; GIL released, all cores), so it renders and tabulates
like any model. RGB files answer in their own RGB channels; spectral files answer at any
wavelengths (linear between the file's, held beyond its ends), and in linear sRGB from
the default spectral grid when none are asked for. ``reference`` is the numpy statement
of the same arithmetic (bsdflab/measured/rgl_reference.py), kept for cross-checks.
"""
from __future__ import annotations

import os
from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF
from bsdflab.lobes import Lobe
from bsdflab.measured import store
from bsdflab.measured.rgl_file import RGLData, read_rgl
from bsdflab.measured.rgl_reference import RGLReference

RGB_NODES = (0.0, 1.0, 2.0)


class Measured(BSDF):
    """A measured (RGL ``.bsdf``) material.

    Parameters
    ----------
    path : str or path
        The ``.bsdf`` file (RGB or spectral, isotropic). It is read and checked at once;
        a bad file is a ``ValueError`` naming the field.
    hash : str
        Instead of ``path``: the SHA-256 of a file kept in a store folder
        (bsdflab.measured.store; the service's uploads); the model's dict then names it by
        this hash, never by a path.
    """

    type_name = "measured"
    # Its dict names a file on this machine: an HTTP request must never carry it (the service
    # resolves measured files by artefact hash; see docs/measured.md).
    reads_path = True

    def __init__(self, path=None, hash=None):   # noqa: A002 -- the dict's key
        super().__init__()
        if (path is None) == (hash is None):
            raise ValueError("give exactly one of path (a file) or hash (a stored upload's SHA-256)")
        self.hash = hash
        if hash is not None:
            path = store.locate(hash, ".bsdf", "RGL .bsdf file")
        if not isinstance(path, (str, os.PathLike)):
            raise ValueError(f"path must be the path of an RGL .bsdf file, got {type(path).__name__}")
        self.path = os.fspath(path)
        self.data = read_rgl(self.path)
        self._reference = None

    @property
    def reference(self) -> RGLReference:
        """The numpy evaluation of the same file (for cross-checks)."""
        if self._reference is None:
            self._reference = RGLReference(self.data)
        return self._reference

    @property
    def spectral(self) -> bool:
        return self.data.spectral

    @property
    def lobes(self) -> Lobe:
        return Lobe.GLOSSY_REFLECTION

    def _channels(self, wavelengths):
        if not self.spectral:
            if wavelengths is not None:
                raise ValueError("this RGL file stores RGB; wavelengths must be None")
            return np.array(RGB_NODES), None
        return super()._channels(wavelengths)

    def _build(self, wavelengths: np.ndarray):
        if not self.spectral and tuple(float(w) for w in wavelengths) != RGB_NODES:
            raise ValueError("this RGL file stores RGB, not spectra: it answers in RGB only (a "
                             "spectral caller, e.g. tabulate with wavelengths, needs a spectral file)")
        return core_of(self.data, wavelengths)

    def render_core(self):
        if not self.spectral:
            return self._core(np.array(RGB_NODES)), None
        return super().render_core()

    def _params(self) -> dict[str, Any]:
        return {"path": self.path} if self.hash is None else {"hash": self.hash}


def core_of(d: RGLData, channel_ids) -> _core.MeasuredBSDF:
    """The C++ BSDF of a checked file, answering at ``channel_ids`` (nm, or 0, 1, 2 for RGB)."""
    flat = lambda a: np.ascontiguousarray(a, dtype=np.float32).ravel().tolist()
    nodes = d.wavelengths.astype(float).tolist() if d.spectral else list(RGB_NODES)
    return _core.MeasuredBSDF(
        [float(c) for c in channel_ids], bool(d.jacobian), d.theta_i.astype(float).tolist(),
        d.phi_i.astype(float).tolist(), nodes, flat(d.ndf), d.ndf.shape[0], d.ndf.shape[1],
        flat(d.sigma), d.sigma.shape[0], d.sigma.shape[1], flat(d.vndf), d.vndf.shape[2], d.vndf.shape[3],
        flat(d.luminance), flat(d.values), d.values.shape[-1])
