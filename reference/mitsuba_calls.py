"""Run a Mitsuba 3 BSDF's eval, pdf and sample on numpy arrays of queries.

Mitsuba's local frame is bsdflab's (+z normal, wi and wo pointing away), so directions go
in unchanged: ``si.wi = wi`` with an identity shading frame. Mitsuba's ``eval`` returns
f * cos(theta_o), the same quantity as bsdflab's ``eval``. Inputs are passed as float32
(Mitsuba's precision); results come back as float64 arrays.

With a vectorised variant each method is one call over all N queries; with scalar_rgb
the loop runs here, in Python (fine for a few thousand queries).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.lobes import Lobe
from bsdflab.reference.mitsuba_env import mitsuba


@dataclass(frozen=True)
class MitsubaResults:
    eval: np.ndarray          # (N, 3) f |cos theta_o| for the pairs (wi, wo)
    pdf: np.ndarray           # (N,) solid-angle density of wo given wi
    sample_wo: np.ndarray     # (N, 3) direction sampled for wi with uniforms (u1, u2)
    sample_weight: np.ndarray  # (N, 3) its weight f |cos theta_o| / pdf (0 if none)
    sample_pdf: np.ndarray    # (N,)
    sample_type: np.ndarray   # (N,) Mitsuba BSDFFlags bit of the sampled lobe
    sample_eta: np.ndarray    # (N,) relative index crossed


def query(plugin: dict, wi: np.ndarray, wo: np.ndarray, u1: np.ndarray,
          u2: np.ndarray, wavelengths: np.ndarray | None = None) -> MitsubaResults:
    """Evaluate, and sample, the Mitsuba BSDF described by ``plugin`` (a load_dict dict).

    wi, wo: (N, 3); u1: (N,); u2: (N, 2). All are rounded to float32 here.
    wavelengths: (N,) nm, for a spectral variant that the caller made active (all of a
    query's wavelengths are set to it; results keep the first three of them). None: the
    reference RGB variant.
    """
    f32 = lambda a: np.ascontiguousarray(a, dtype=np.float32)
    wi, wo, u1, u2 = f32(wi), f32(wo), f32(u1), f32(u2)
    if wavelengths is None:
        mi = mitsuba()
    else:
        import mitsuba as mi

        if not mi.is_spectral:
            raise ValueError(f"wavelengths need a spectral variant active, not {mi.variant()!r}")
        wavelengths = f32(wavelengths)
    bsdf = mi.load_dict(plugin)
    if mi.variant().startswith("llvm"):
        return _query_vectorised(mi, bsdf, wi, wo, u1, u2, wavelengths)
    return _query_scalar(mi, bsdf, wi, wo, u1, u2, wavelengths)


def mitsuba_answers(plugin: dict, q) -> dict[str, np.ndarray]:
    """Mitsuba's answers to the queries ``q`` (query_sets.Queries) in the form of
    ``query_sets.bsdflab_answers``: lobe as bsdflab Lobe bits, 0 where no sample."""
    m = query(plugin, q.wi, q.wo, q.u1, q.u2)
    # A failed sample has zero weight; in vectorised variants its other fields are
    # whatever the masked-off lane computed.
    sampled = np.any(m.sample_weight != 0, axis=1)
    return {"eval": m.eval, "pdf": m.pdf, "wo": m.sample_wo, "weight": m.sample_weight,
            "sample_pdf": m.sample_pdf, "eta": m.sample_eta,
            "lobe": np.where(sampled, lobe_of_flags(m.sample_type), 0)}


def lobe_of_flags(flags: np.ndarray) -> np.ndarray:
    """bsdflab Lobe bits of Mitsuba BSDFFlags lobe bits (-1 for anything else)."""
    f = mitsuba().BSDFFlags
    table = {int(f.DiffuseReflection): Lobe.DIFFUSE_REFLECTION,
             int(f.GlossyReflection): Lobe.GLOSSY_REFLECTION,
             int(f.DeltaReflection): Lobe.DELTA_REFLECTION,
             int(f.DiffuseTransmission): Lobe.DIFFUSE_TRANSMISSION,
             int(f.GlossyTransmission): Lobe.GLOSSY_TRANSMISSION,
             int(f.DeltaTransmission): Lobe.DELTA_TRANSMISSION}
    return np.array([int(table.get(int(t), -1)) for t in flags], dtype=np.int64)


def _identity_frame(mi):
    return mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))


def _query_vectorised(mi, bsdf, wi, wo, u1, u2, wavelengths=None) -> MitsubaResults:
    import drjit as dr

    n = len(wi)
    vec = lambda a: mi.Vector3f(a[:, 0], a[:, 1], a[:, 2])
    # A field a plugin sets to a constant (e.g. pdf = 1) comes back with one lane.
    lanes = lambda v, dtype=np.float64: np.broadcast_to(np.array(v, dtype=dtype), (n,)).copy()
    rows = lambda v: np.stack([lanes(c) for c in list(v)[:3]], axis=1)  # Mitsuba gives (3 or 4, N)
    ctx = mi.BSDFContext()
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = vec(wi)
    si.sh_frame = _identity_frame(mi)
    if wavelengths is not None:
        si.wavelengths = mi.Spectrum(*[mi.Float(wavelengths)] * 4)
    value = bsdf.eval(ctx, si, vec(wo))
    pdf = bsdf.pdf(ctx, si, vec(wo))
    bs, weight = bsdf.sample(ctx, si, mi.Float(u1), mi.Point2f(u2[:, 0], u2[:, 1]))
    return MitsubaResults(
        eval=rows(value), pdf=lanes(pdf), sample_wo=rows(bs.wo), sample_weight=rows(weight),
        sample_pdf=lanes(bs.pdf), sample_type=lanes(bs.sampled_type, np.int64),
        sample_eta=lanes(bs.eta))


def _query_scalar(mi, bsdf, wi, wo, u1, u2, wavelengths=None) -> MitsubaResults:
    n = len(wi)
    out = {k: np.zeros((n, 3)) for k in ("eval", "sample_wo", "sample_weight")}
    out.update({k: np.zeros(n) for k in ("pdf", "sample_pdf", "sample_eta")})
    out["sample_type"] = np.zeros(n, dtype=np.int64)
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    si.sh_frame = _identity_frame(mi)
    for j in range(n):
        if wavelengths is not None:
            si.wavelengths = mi.Spectrum(*[float(wavelengths[j])] * 4)
        si.wi = mi.Vector3f(*wi[j].tolist())
        w = mi.Vector3f(*wo[j].tolist())
        out["eval"][j] = list(bsdf.eval(ctx, si, w))[:3]
        out["pdf"][j] = bsdf.pdf(ctx, si, w)
        bs, weight = bsdf.sample(ctx, si, float(u1[j]), mi.Point2f(*u2[j].tolist()))
        out["sample_wo"][j] = list(bs.wo)
        out["sample_weight"][j] = list(weight)[:3]
        out["sample_pdf"][j] = bs.pdf
        out["sample_type"][j] = int(bs.sampled_type)
        out["sample_eta"][j] = bs.eta
    return MitsubaResults(**out)
