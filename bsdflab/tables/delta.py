"""The delta (unscattered) lobes of a layered model for its table's lookup.

A table stores the scattered part of a layered model (PFMC's and adding-doubling's eval
leave out paths whose every event is a delta one); the lookup adds these back exactly
from the model the table file keeps (its ``model`` dict): the stack's smooth boundaries
and its slabs' extinction, solved per query by 1-D adding in the core
(core/include/bsdflab/table_delta.h derives it). Nothing new is stored in the file."""

from __future__ import annotations

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import from_dict
from bsdflab.layered.stack import Layered


def delta_stack(model: dict, wavelengths: np.ndarray, weights: np.ndarray):
    """(the core's `TableDeltaStack` of a layered model dict, P): the stack at
    ``wavelengths`` (nm) and P (table channels x stack channels, row-major, flat) taking
    its channels to the table's, given ``weights`` (table channels x wavelengths). A
    spectrally flat stack (every boundary's `render_core` one channel, slabs grey) is
    solved at one wavelength with P's row sums: the same answer, 81 times less work.
    (None, []) when the model is not layered or its delta lobes are its boundaries' own
    reflections (e.g. a smooth top over a diffuse base: the exact part already adds the
    top's, through the faster film lookup)."""
    try:
        bsdf = from_dict(model)
    except (ValueError, TypeError):
        return None, []
    if not isinstance(bsdf, Layered):
        return None, []
    wl = np.asarray(wavelengths, dtype=np.float64)
    W = np.asarray(weights, dtype=np.float64)
    models = (*bsdf.interfaces, bsdf.base)
    flat_cores = [m.render_core()[0] for m in models]
    sigma_a = [np.asarray(s.sigma_a_at(wl), dtype=np.float64) for s in bsdf.slabs]
    if all(c.channels == 1 for c in flat_cores) and all(np.all(a == a[0]) for a in sigma_a):
        boundaries, sigma_a, P = flat_cores, [a[:1] for a in sigma_a], W.sum(axis=1, keepdims=True)
    else:
        boundaries, P = [m._core(wl) for m in models], W
    # Scattering takes light out of the unscattered beam as absorption does.
    sigma_t = [list(a + s.sigma_s) for a, s in zip(sigma_a, bsdf.slabs)]
    stack = _core.TableDeltaStack(boundaries, thickness_um=[s.thickness_um for s in bsdf.slabs], sigma_t=sigma_t)
    return (stack, P.ravel().tolist()) if stack.extends else (None, [])
