"""The fields of an RGL ``.bsdf`` material and their checks (Dupuy & Jakob 2018; the layout
Mitsuba 3's ``measured`` plugin reads, ``src/bsdfs/measured.cpp``). See docs/measured.md.

=============  =======  =====================================  ===============================
field          dtype    shape                                  meaning
=============  =======  =====================================  ===============================
description    uint8    (n,)                                   UTF-8 text
jacobian       uint8    (1,)                                   1: values are divided by
                                                               D(m) / (4 sigma(wi))
theta_i        float32  (n_theta_i,)                           incident elevations, rad
phi_i          float32  (n_phi_i,)                             incident azimuths, rad
                                                               (<= 2 entries: isotropic)
ndf            float32  (n_phi_m, n_theta_m)                   D(m) on u = (sqrt(2 theta/pi),
                                                               (phi + pi) / 2pi)
sigma          float32  (n_phi_s, n_theta_s)                   projected area sigma(wi),
                                                               same u-mapping
vndf           float32  (n_phi_i, n_theta_i, n_phi_m', n_t_m')  visible-normal density in u
luminance      float32  (n_phi_i, n_theta_i, n, n)              sampling density on the
                                                               VNDF's unit square
rgb            float32  (n_phi_i, n_theta_i, 3, n, n)           values (RGB files), or
spectra        float32  (n_phi_i, n_theta_i, n_wl, n, n)        values (spectral files) with
wavelengths    float32  (n_wl,)                                 their wavelengths, nm
=============  =======  =====================================  ===============================

``check_fields`` enforces this (as Mitsuba does) and the meaning bsdflab relies on: finite
values, non-negative densities with a positive integral per slice, increasing nodes, an
isotropic file. Every failure is a ``ValueError`` naming the field.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bsdflab.measured.tensor_file import read_tensor_file

COMMON = ("description", "jacobian", "theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance")
# Cap on the values array (floats), far above the RGL database's largest (~1e7).
MAX_VALUES = 1 << 28


@dataclass(frozen=True)
class RGLData:
    """A checked RGL material: the file's arrays (float32 kept as is)."""

    description: str
    jacobian: bool
    theta_i: np.ndarray      # (n_theta_i,) rad
    phi_i: np.ndarray        # (n_phi_i,) rad
    ndf: np.ndarray          # (n_phi_m, n_theta_m)
    sigma: np.ndarray        # (n_phi_s, n_theta_s)
    vndf: np.ndarray         # (n_phi_i, n_theta_i, ny, nx)
    luminance: np.ndarray    # (n_phi_i, n_theta_i, n, n)
    values: np.ndarray       # (n_phi_i, n_theta_i, C, n, n)
    wavelengths: np.ndarray | None  # (C,) nm for spectral files; None for RGB

    @property
    def spectral(self) -> bool:
        return self.wavelengths is not None

    def fields(self) -> dict:
        """The tensor-file fields, in the order the writer stores them."""
        out = {"description": self.description,
               "jacobian": np.array([1 if self.jacobian else 0], dtype=np.uint8)}
        for k in ("theta_i", "phi_i", "ndf", "sigma", "vndf", "luminance"):
            out[k] = np.asarray(getattr(self, k), dtype=np.float32)
        if self.spectral:
            out["spectra"] = np.asarray(self.values, dtype=np.float32)
            out["wavelengths"] = np.asarray(self.wavelengths, dtype=np.float32)
        else:
            out["rgb"] = np.asarray(self.values, dtype=np.float32)
        return out


def read_rgl(path) -> RGLData:
    """Read and check the RGL ``.bsdf`` file at ``path``."""
    return check_fields(read_tensor_file(path), name=str(path))


def check_fields(fields: dict, name: str = "RGL material") -> RGLData:
    """An ``RGLData`` from tensor-file fields, or a ``ValueError`` naming the bad field."""
    spectral = "wavelengths" in fields
    values_key = "spectra" if spectral else "rgb"
    for key in (*COMMON, values_key):
        if key not in fields:
            other = " (a spectral file needs 'spectra' and 'wavelengths')" if key == "rgb" else ""
            raise ValueError(f"{name}: field {key!r} is missing{other}")

    def arr(key: str, dtype, ndim: int) -> np.ndarray:
        a = fields[key]
        if a.dtype != np.dtype(dtype):
            raise ValueError(f"{name}: field {key!r} must be {np.dtype(dtype).name}, got {a.dtype.name}")
        if a.ndim != ndim:
            raise ValueError(f"{name}: field {key!r} must be {ndim}-dimensional, got shape {a.shape}")
        if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
            raise ValueError(f"{name}: field {key!r} holds NaN or infinite values")
        return a

    description = arr("description", np.uint8, 1).tobytes().decode("utf-8", errors="replace")
    jac = arr("jacobian", np.uint8, 1)
    if jac.shape != (1,) or int(jac[0]) not in (0, 1):
        raise ValueError(f"{name}: field 'jacobian' must hold one byte, 0 or 1")
    theta_i = arr("theta_i", np.float32, 1)
    phi_i = arr("phi_i", np.float32, 1)
    ndf, sigma = arr("ndf", np.float32, 2), arr("sigma", np.float32, 2)
    vndf, lum = arr("vndf", np.float32, 4), arr("luminance", np.float32, 4)
    values = fields[values_key]
    if values.dtype == np.float32 and values.ndim == 5 and values.size > MAX_VALUES:
        raise ValueError(f"{name}: field {values_key!r} has {values.size} values; at most {MAX_VALUES}")
    values = arr(values_key, np.float32, 5)
    wavelengths = arr("wavelengths", np.float32, 1) if spectral else None

    _nodes(name, "theta_i", theta_i, 0.0, math.pi / 2 + 1e-3)
    if len(phi_i) > 2:
        raise ValueError(f"{name}: field 'phi_i' has {len(phi_i)} entries: an anisotropic material; "
                         f"bsdflab reads isotropic RGL files only (phi_i with 1 or 2 entries)")
    _nodes(name, "phi_i", phi_i, -2 * math.pi, 2 * math.pi)
    n_phi, n_theta = len(phi_i), len(theta_i)
    for key, a in (("ndf", ndf), ("sigma", sigma)):
        if min(a.shape) < 2:
            raise ValueError(f"{name}: field {key!r} needs at least 2 x 2 nodes, got shape {a.shape}")
    for key, a in (("vndf", vndf), ("luminance", lum)):
        if a.shape[:2] != (n_phi, n_theta):
            raise ValueError(f"{name}: field {key!r} has shape {a.shape}; its first axes must be "
                             f"(len(phi_i), len(theta_i)) = ({n_phi}, {n_theta})")
        if min(a.shape[2:]) < 2:
            raise ValueError(f"{name}: field {key!r} needs at least 2 x 2 nodes per slice, got shape {a.shape}")
    if lum.shape[2] != lum.shape[3]:
        raise ValueError(f"{name}: field 'luminance' must have square slices, got shape {lum.shape}")
    n_channels = len(wavelengths) if spectral else 3
    expect = (n_phi, n_theta, n_channels, *lum.shape[2:])
    if values.shape != expect:
        raise ValueError(f"{name}: field {values_key!r} has shape {values.shape}, expected {expect} "
                         f"(phi_i, theta_i, {'wavelengths' if spectral else 'RGB'}, luminance's grid)")
    if spectral:
        _nodes(name, "wavelengths", wavelengths, 1.0, 1e5)
    for key, a in (("ndf", ndf), ("sigma", sigma), ("vndf", vndf), ("luminance", lum)):
        if np.any(a < 0):
            raise ValueError(f"{name}: field {key!r} holds negative values (it is a density)")
    if np.any(sigma <= 0):
        raise ValueError(f"{name}: field 'sigma' must be positive (it divides the values)")
    for key, a in (("vndf", vndf), ("luminance", lum)):
        if np.any(a.reshape(n_phi * n_theta, -1).sum(axis=1) <= 0):
            raise ValueError(f"{name}: field {key!r} has a slice that is zero everywhere (no density to sample)")
    if spectral and np.any(values < 0):
        raise ValueError(f"{name}: field 'spectra' holds negative values")
    return RGLData(description=description, jacobian=bool(jac[0]), theta_i=theta_i, phi_i=phi_i,
                   ndf=ndf, sigma=sigma, vndf=vndf, luminance=lum, values=values,
                   wavelengths=wavelengths)


def _nodes(name: str, key: str, a: np.ndarray, lo: float, hi: float) -> None:
    if len(a) < 1:
        raise ValueError(f"{name}: field {key!r} is empty")
    if np.any(np.diff(a.astype(np.float64)) <= 0):
        raise ValueError(f"{name}: field {key!r} must be strictly increasing")
    if a.min() < lo or a.max() > hi:
        raise ValueError(f"{name}: field {key!r} must lie in [{lo:g}, {hi:g}], got [{a.min():g}, {a.max():g}]")
