"""Lobe flags shared with the C++ core (one bit per kind x side)."""
from __future__ import annotations

import enum

from bsdflab import _core


class Lobe(enum.IntFlag):
    """Which part of a BSDF a call may use, or which part produced a sample.

    Bits match ``bsdflab._core.LobeBits``. Combine with ``|``; e.g.
    ``bsdf.eval(wi, wo, lobes=Lobe.REFLECTION)`` isolates reflection.
    """

    NONE = 0
    DIFFUSE_REFLECTION = int(_core.LobeBits.DiffuseReflection)
    GLOSSY_REFLECTION = int(_core.LobeBits.GlossyReflection)
    DELTA_REFLECTION = int(_core.LobeBits.DeltaReflection)
    DIFFUSE_TRANSMISSION = int(_core.LobeBits.DiffuseTransmission)
    GLOSSY_TRANSMISSION = int(_core.LobeBits.GlossyTransmission)
    DELTA_TRANSMISSION = int(_core.LobeBits.DeltaTransmission)
    REFLECTION = DIFFUSE_REFLECTION | GLOSSY_REFLECTION | DELTA_REFLECTION
    TRANSMISSION = DIFFUSE_TRANSMISSION | GLOSSY_TRANSMISSION | DELTA_TRANSMISSION
    DIFFUSE = DIFFUSE_REFLECTION | DIFFUSE_TRANSMISSION
    GLOSSY = GLOSSY_REFLECTION | GLOSSY_TRANSMISSION
    DELTA = DELTA_REFLECTION | DELTA_TRANSMISSION
    SMOOTH = DIFFUSE | GLOSSY
    ALL = REFLECTION | TRANSMISSION
