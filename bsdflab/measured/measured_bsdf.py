"""``Measured``: an RGL ``.bsdf`` material (Dupuy & Jakob 2018) as a bsdflab BSDF.

Reflection only, one-sided (zero when either direction is below the surface), one glossy
lobe -- as Mitsuba 3's ``measured`` plugin. RGB files answer in their own RGB channels;
spectral files answer at any wavelengths (linear between the file's, held beyond its
ends), and in linear sRGB from the default spectral grid when none are asked for.
"""
from __future__ import annotations

import os
from typing import Any

import numpy as np

from bsdflab.bsdfs.base import BSDF
from bsdflab.lobes import Lobe
from bsdflab.measured.numpy_core import NumpyCore
from bsdflab.measured.rgl_file import read_rgl
from bsdflab.measured.rgl_reference import RGLReference



class _Channels:
    """An RGLReference answering at fixed channels (wavelengths, or the file's RGB)."""

    def __init__(self, ref: RGLReference, channels):
        self.ref, self.channels = ref, channels

    def eval(self, wi, wo):
        return self.ref.eval(wi, wo, self.channels)

    def pdf(self, wi, wo):
        return self.ref.pdf(wi, wo)

    def sample(self, wi, u2):
        return self.ref.sample(wi, u2, self.channels)


class Measured(BSDF):
    """A measured (RGL ``.bsdf``) material.

    Parameters
    ----------
    path : str or path
        The ``.bsdf`` file (RGB or spectral, isotropic). It is read and checked at once;
        a bad file is a ``ValueError`` naming the field.
    """

    type_name = "measured"

    def __init__(self, path):
        super().__init__()
        if not isinstance(path, (str, os.PathLike)):
            raise ValueError(f"path must be the path of an RGL .bsdf file, got {type(path).__name__}")
        self.path = os.fspath(path)
        self.data = read_rgl(self.path)
        self.reference = RGLReference(self.data)

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
            return np.arange(3, dtype=float), None
        return super()._channels(wavelengths)

    def _build(self, wavelengths: np.ndarray):
        channels = None if not self.spectral else wavelengths
        return NumpyCore(_Channels(self.reference, channels), len(wavelengths), Lobe.GLOSSY_REFLECTION)

    def render_core(self):
        raise ValueError("the renderer needs a C++ BSDF; Measured is evaluated in numpy in this "
                         "version (docs/measured.md): tabulate it (bsdflab.tables.tabulate) and "
                         "render the table")

    def _params(self) -> dict[str, Any]:
        return {"path": self.path}


