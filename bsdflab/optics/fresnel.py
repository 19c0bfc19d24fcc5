"""Fresnel coefficients of a single planar interface, real or complex indices.

Sign convention (Born & Wolf; the same as the `tmm` package), for light going from a
medium of index n_i into one of index n_t (indices n + i k, k >= 0 absorbing; n in
[1e-3, 1e3] and k <= 1e3, docs/limits.md):

    r_s = (n_i cos_i - n_t cos_t) / (n_i cos_i + n_t cos_t)
    r_p = (n_t cos_i - n_i cos_t) / (n_t cos_i + n_i cos_t)
    t_s = 2 n_i cos_i / (n_i cos_i + n_t cos_t)
    t_p = 2 n_i cos_i / (n_t cos_i + n_i cos_t)

cos_t follows from Snell's law with complex arithmetic, on the branch of a forward or
decaying wave, so total internal reflection and absorbing media need no special cases.
Energy goes with squared magnitudes: R = |r|^2 per polarisation, and the unpolarised
reflectance is the mean of R_s and R_p (averaging the amplitudes instead is not an energy).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from bsdflab import _core
from bsdflab.util.args import MAX_EXTINCTION, MAX_IOR, MIN_IOR


class Amplitudes(NamedTuple):
    r_s: np.ndarray
    r_p: np.ndarray
    t_s: np.ndarray
    t_p: np.ndarray
    cos_t: np.ndarray


class Reflectance(NamedTuple):
    s: np.ndarray
    p: np.ndarray
    unpolarised: np.ndarray


def _complex(name, value):
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be a real or complex number or array")
    try:
        a = np.asarray(value, dtype=np.complex128)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a real or complex number or array") from None
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite (found NaN or infinity)")
    return a


def _inputs(cos_i, n_i, n_t):
    c = _complex("cos_i", cos_i)
    ni = _complex("n_i", n_i)
    nt = _complex("n_t", n_t)
    if np.any(c.real < 0) or np.any(c.real > 1) or np.any(c.imag != 0):
        raise ValueError("cos_i must be real and in [0, 1] (light arrives from the n_i side)")
    for name, n in (("n_i", ni), ("n_t", nt)):
        if np.any(n.real <= 0):
            raise ValueError(f"{name} must have a real part > 0")
        if np.any(n.imag < 0):
            raise ValueError(f"{name} must have an imaginary part (k) >= 0")
        if np.any(n.real < MIN_IOR) or np.any(n.real > MAX_IOR) or np.any(n.imag > MAX_EXTINCTION):
            raise ValueError(f"{name} must have a real part in [{MIN_IOR:g}, {MAX_IOR:g}] and an "
                             f"imaginary part <= {MAX_EXTINCTION:g} (docs/limits.md)")
    try:
        c, ni, nt = np.broadcast_arrays(c, ni, nt)
    except ValueError:
        raise ValueError(f"cos_i, n_i and n_t do not broadcast: shapes {c.shape}, "
                         f"{ni.shape}, {nt.shape}") from None
    return c, ni, nt


def fresnel_amplitudes(cos_i, n_i, n_t) -> Amplitudes:
    """Complex amplitude coefficients (r_s, r_p, t_s, t_p) and the complex cos_t.

    Parameters broadcast against each other; results have the broadcast shape.
    """
    c, ni, nt = _inputs(cos_i, n_i, n_t)
    shape = c.shape
    r_s, r_p, t_s, t_p, cos_t = (np.reshape(a, shape) for a in
                                 _core.fresnel_amplitudes(np.ravel(ni), np.ravel(nt), np.ravel(c)))
    # Equal indices are no interface: r = 0, t = 1 -- also at grazing incidence, where the
    # general formula is 0 / 0.
    same = ni == nt
    if np.any(same):
        r_s, r_p, t_s, t_p, cos_t = (np.where(same, v, a) for v, a in
                                     ((0, r_s), (0, r_p), (1, t_s), (1, t_p), (c, cos_t)))
    return Amplitudes(r_s, r_p, t_s, t_p, cos_t)


def fresnel_reflectance(cos_i, n_i, n_t) -> Reflectance:
    """Reflectances R_s = |r_s|^2, R_p = |r_p|^2 and the unpolarised mean."""
    a = fresnel_amplitudes(cos_i, n_i, n_t)
    rs, rp = np.abs(a.r_s) ** 2, np.abs(a.r_p) ** 2
    return Reflectance(rs, rp, 0.5 * (rs + rp))


def fresnel_transmittance(cos_i, n_i, n_t) -> Reflectance:
    """Transmittances T = Re(n_t cos_t) / Re(n_i cos_i) |t|^2 (s) and the p analogue
    Re(n_t conj(cos_t)) / Re(n_i conj(cos_i)) |t_p|^2, for a non-absorbing incident medium.
    T_s + R_s = 1 and T_p + R_p = 1 at a lossless interface."""
    c, ni, nt = _inputs(cos_i, n_i, n_t)
    a = fresnel_amplitudes(c, ni, nt)
    with np.errstate(divide="ignore", invalid="ignore"):
        ts = np.real(nt * a.cos_t) / np.real(ni * c) * np.abs(a.t_s) ** 2
        tp = np.real(nt * np.conj(a.cos_t)) / np.real(ni * np.conj(c)) * np.abs(a.t_p) ** 2
    ts, tp = np.nan_to_num(ts), np.nan_to_num(tp)
    same = ni == nt  # no interface: everything passes, grazing included (0 / 0 above)
    ts, tp = np.where(same, 1.0, ts), np.where(same, 1.0, tp)
    return Reflectance(ts, tp, 0.5 * (ts + tp))
