"""Choose Mitsuba 3's variant for the reference cross-checks, once per process.

Preference: ``llvm_ad_rgb`` (vectorised: thousands of BSDF queries in one kernel) when
Dr.Jit's LLVM backend runs on LLVM 19, else ``scalar_rgb`` (one query per Python call).
LLVM 19 is what these checks were verified with; Debian's default LLVM 15 crashes the
llvm_ad_* variants, so any other version falls back to scalar.

Dr.Jit reads ``DRJIT_LIBLLVM_PATH`` when it loads LLVM, so it is set here before the
first import of drjit/mitsuba (an explicit value from the environment is kept).
Set ``BSDFLAB_MITSUBA_VARIANT`` to 'scalar_rgb' or 'llvm_ad_rgb' to force a choice (the
spectral cross-checks then use 'scalar_spectral' or 'llvm_ad_spectral').
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

from bsdflab.util.extras import require

LLVM_VARIANT = "llvm_ad_rgb"
SCALAR_VARIANT = "scalar_rgb"
VARIANTS = (LLVM_VARIANT, SCALAR_VARIANT)
# For spectral-mode cross-checks (reference/mitsuba_spectral.py), chosen by the same rule.
LLVM_SPECTRAL_VARIANT = "llvm_ad_spectral"
SCALAR_SPECTRAL_VARIANT = "scalar_spectral"
SPECTRAL_VARIANTS = (LLVM_SPECTRAL_VARIANT, SCALAR_SPECTRAL_VARIANT)
VERIFIED_LLVM_MAJOR = 19

# Where Debian's libllvm19 puts the shared library (the versioned file and its links).
LIBLLVM_19_CANDIDATES = (
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
    "/usr/lib/llvm-19/lib/libLLVM.so.1",
    "/usr/lib/llvm-19/lib/libLLVM-19.so",
    "/usr/lib/llvm-19/lib/libLLVM.so",
)

_chosen: str | None = None


def find_libllvm19() -> str | None:
    """The real file (links resolved) of an installed libLLVM 19, or None."""
    for candidate in LIBLLVM_19_CANDIDATES:
        p = Path(candidate)
        if p.exists():
            return str(p.resolve())
    return None


def _point_drjit_at_llvm19() -> None:
    if "DRJIT_LIBLLVM_PATH" in os.environ or "drjit" in sys.modules:
        return  # the user's choice, or too late to matter
    lib = find_libllvm19()
    if lib is not None:
        os.environ["DRJIT_LIBLLVM_PATH"] = lib


def _llvm_usable() -> bool:
    import drjit as dr

    try:
        if not dr.has_backend(dr.JitBackend.LLVM):
            return False
        return dr.detail.llvm_version()[0] == VERIFIED_LLVM_MAJOR
    except Exception:  # no LLVM backend compiled in, or it failed to load
        return False


def _choose() -> str:
    from bsdflab.util.settings import library_settings

    forced = library_settings().mitsuba_variant   # BSDFLAB_MITSUBA_VARIANT
    if forced is not None:
        if forced not in VARIANTS:
            raise ValueError(f"BSDFLAB_MITSUBA_VARIANT must be one of {', '.join(VARIANTS)}; "
                             f"got {forced!r}")
        return forced
    return LLVM_VARIANT if _llvm_usable() else SCALAR_VARIANT


def mitsuba():
    """The ``mitsuba`` module with the reference variant active (chosen on first call;
    re-activated if other code switched variants since)."""
    global _chosen
    _point_drjit_at_llvm19()
    mi = require("mitsuba", "mitsuba")

    if _chosen is None:
        _chosen = _choose()
    if mi.variant() != _chosen:
        mi.set_variant(_chosen)
    return mi


def variant() -> str:
    """The Mitsuba variant the reference checks use: 'llvm_ad_rgb' or 'scalar_rgb'."""
    mitsuba()
    assert _chosen is not None
    return _chosen


def spectral_variant() -> str:
    """The spectral variant matching the reference variant: 'llvm_ad_spectral' where the
    LLVM one is used, else 'scalar_spectral'."""
    return LLVM_SPECTRAL_VARIANT if variant() == LLVM_VARIANT else SCALAR_SPECTRAL_VARIANT


def is_vectorised() -> bool:
    """True when one Mitsuba call evaluates a whole array of queries."""
    return variant() == LLVM_VARIANT
