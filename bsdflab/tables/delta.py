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


def delta_stack(model: dict, wavelengths: np.ndarray):
    """The core's `TableDeltaStack` of a layered model dict at ``wavelengths`` (nm), or None
    when the model is not layered or its delta lobes are its boundaries' own reflections
    (e.g. a smooth top over a diffuse base: the exact part already adds the top's, through
    the faster film lookup)."""
    try:
        bsdf = from_dict(model)
    except (ValueError, TypeError):
        return None
    if not isinstance(bsdf, Layered):
        return None
    wl = np.asarray(wavelengths, dtype=np.float64)
    boundaries = [m._core(wl) for m in (*bsdf.interfaces, bsdf.base)]
    # Scattering takes light out of the unscattered beam as absorption does.
    sigma_t = [list(np.asarray(s.sigma_a_at(wl), dtype=np.float64) + s.sigma_s) for s in bsdf.slabs]
    stack = _core.TableDeltaStack(boundaries, thickness_um=[s.thickness_um for s in bsdf.slabs], sigma_t=sigma_t)
    return stack if stack.extends else None
