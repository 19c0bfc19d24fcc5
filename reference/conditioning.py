"""Which queries float32 can answer to the target, and how far off it may be elsewhere.

A float32 code is accurate to about the rounding of its inputs and intermediates. Each
pair's *sensitivity* is how far bsdflab's own float64 result moves when

  * its inputs move by INPUT_PERTURBATION = 8 float32 ulps: the index ratio (via
    ext_ior) and the direction cosines relatively (``perturbations``: z only, or every
    component for microfacet models, whose half vectors mix all of them), the uniforms
    absolutely (they go through 2u - 1); every sign combination;
  * and, for a dielectric, under two internal roundings no input reaches: a lobe
    probability formed as a complement 1 - p (relative error x (1 - p) / p), and
    1 - cos^2 theta_i inside Snell's law (see ``_dielectric_rounding``).

A pair is *ill-conditioned* when a sensitivity exceeds TARGET or its sampled lobe flips
under the perturbations; it is then held to the bound target + sensitivity, the rest to
the target. ``reasons`` names the mechanism of each ill-conditioned pair.
"""
from __future__ import annotations

import itertools

import numpy as np

from bsdflab.bsdfs import from_dict
from bsdflab.lobes import Lobe
from bsdflab.reference.comparison import QUANTITIES, TARGET, errors_between, rel_error
from bsdflab.reference.query_sets import bsdflab_answers

UNIT_ROUNDOFF_F32 = 2.0**-24
INPUT_PERTURBATION = 8 * UNIT_ROUNDOFF_F32
ILL_CONDITIONED = TARGET    # sensitivity above which float32 may miss the target

NEAR_CRITICAL_COS2 = 0.05   # |cos^2 theta_t| below this is reported as "near critical"
GRAZING_COS = 1e-2          # |cos theta| below this is reported as "grazing"
RARE_LOBE = 0.1             # a dielectric lobe probability below this is "rare"
SAMPLED_LOW_COS = 0.5       # a diffuse sample below this is "towards the horizon"


def _perturbed(d: dict, q, sign_ior: float, sign_dir, sign_u: float):
    d = dict(d)
    if sign_ior:
        d["ext_ior"] = d["ext_ior"] * (1 + sign_ior * INPUT_PERTURBATION)
    scale_wi, scale_wo = 1 + np.asarray(sign_dir, dtype=float) * INPUT_PERTURBATION
    shift = lambda u: np.clip(u + sign_u * INPUT_PERTURBATION, 0.0, 1.0)
    return from_dict(d), type(q)(wi=q.wi * scale_wi, wo=q.wo * scale_wo, u1=shift(q.u1),
                                 u2=shift(q.u2))


def perturbations(d: dict, q, every_component: bool = False):
    """(BSDF, queries) for each sign combination of the input perturbations: ext_ior (where
    float32 rounds the index ratio), the uniforms, and the directions' z components, the
    same for wi and wo -- or, with ``every_component``, each of x, y and z independently,
    for wo the same as for wi or the opposite (a half vector wi + eta wo, which can
    cancel, moves only when they differ)."""
    signs_ior = (-1.0, 1.0) if _ior_is_rounded(d) else (0.0,)
    if every_component:
        signs_dir = [(s, t * np.array(s)) for s in itertools.product((-1.0, 1.0), repeat=3)
                     for t in (-1.0, 1.0)]
    else:
        signs_dir = [((0.0, 0.0, s), (0.0, 0.0, s)) for s in (-1.0, 1.0)]
    for s_ior, s_dir, s_u in itertools.product(signs_ior, signs_dir, (-1.0, 1.0)):
        yield _perturbed(d, q, s_ior, s_dir, s_u)


def _ior_is_rounded(d: dict) -> bool:
    """Whether float32 rounds the model's index ratio. An index-matched dielectric's
    ratio is exactly 1 in float32 too (Mitsuba special-cases it), so it is not moved."""
    if "ext_ior" not in d:
        return False
    return not (d["type"] == "dielectric" and d["int_ior"] == d["ext_ior"])


def sensitivity(d: dict, q, base: dict, channels) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Per pair and quantity, the largest change of bsdflab's results (``base``, for the
    BSDF dict ``d`` on queries ``q``) under float32-sized roundings; and the pairs whose
    sampled lobe (or whether a sample exists at all) flips under them."""
    sens = {k: np.zeros(len(q.wi)) for k in QUANTITIES}
    flips = np.zeros(len(q.wi), dtype=bool)
    valid = base["lobe"] != 0
    for bsdf_p, q_p in perturbations(d, q):
        r = bsdflab_answers(bsdf_p, q_p, channels)
        same = r["lobe"] == base["lobe"]
        flips |= ~same
        e = errors_between(r, base, same & valid)
        if d["type"] == "dielectric":
            # The two lobes are complementary: where the perturbed call picked the other
            # lobe with probability p', this lobe's probability there is 1 - p'.
            other = ~same & valid & (r["lobe"] != 0)
            e["sample_pdf"] = np.where(other, rel_error(1 - r["sample_pdf"], base["sample_pdf"]),
                                       e["sample_pdf"])
        for k in QUANTITIES:
            sens[k] = np.maximum(sens[k], e[k])
    if d["type"] == "dielectric":
        for k, v in _dielectric_rounding(d, q, base).items():
            sens[k] = np.maximum(sens[k], v)
    return sens, flips


def cos2_t(d: dict, wi: np.ndarray) -> np.ndarray | None:
    """cos^2 theta_t by Snell's law for a dielectric (negative: total internal
    reflection); None for other models."""
    if d["type"] != "dielectric":
        return None
    eta = d["int_ior"] / d["ext_ior"]
    eta_ti = np.where(wi[:, 2] >= 0, 1 / eta, eta)
    return 1 - eta_ti**2 * (1 - wi[:, 2] ** 2)


def _dielectric_rounding(d: dict, q, base: dict) -> dict[str, np.ndarray]:
    """Two roundings inside a float32 dielectric that input perturbations do not reach:
      * lobe probabilities R and T = 1 - R: one is formed from the other, so its relative
        rounding is amplified by (1 - p) / p (a rare lobe);
      * cos^2 theta_t = 1 - eta_ti^2 (1 - cos^2 theta_i): 1 - cos^2 theta_i carries an
        absolute rounding, which moves cos theta_t by up to sqrt(rounding) at grazing
        through an index-matched interface (whose ratio itself is exact)."""
    p = base["sample_pdf"]
    with np.errstate(divide="ignore", invalid="ignore"):
        rare = np.where(p > 0, INPUT_PERTURBATION * (1 - p) / p, 0.0)
    c2 = cos2_t(d, q.wi)
    eta = d["int_ior"] / d["ext_ior"]
    eta_ti2 = np.where(q.wi[:, 2] >= 0, 1 / eta, eta) ** 2
    moved = INPUT_PERTURBATION * eta_ti2 * (1 - q.wi[:, 2] ** 2)
    ct = np.sqrt(np.maximum(c2, 0))
    shift = np.maximum(np.abs(np.sqrt(np.maximum(c2 + moved, 0)) - ct),
                       np.abs(np.sqrt(np.maximum(c2 - moved, 0)) - ct))
    refracted = base["lobe"] == int(Lobe.DELTA_TRANSMISSION)
    return {"sample_pdf": rare, "direction": np.where(refracted, shift, 0.0)}


def reasons(d: dict, q, base: dict, idx, flips) -> list[str]:
    """Why float32 cannot resolve each pair in ``idx``, by configuration."""
    c2 = cos2_t(d, q.wi)
    dense = None
    if c2 is not None:
        eta = d["int_ior"] / d["ext_ior"]
        dense = np.where(q.wi[:, 2] >= 0, eta < 1, eta > 1)
    sampled_z, p = np.abs(base["wo"][:, 2]), base["sample_pdf"]
    out = []
    for j in idx:
        if c2 is not None and abs(c2[j]) < NEAR_CRITICAL_COS2:
            out.append(f"near the critical angle (|cos^2 theta_t| < {NEAR_CRITICAL_COS2:g}: "
                       "cos theta_t = sqrt(1 - eta^2 sin^2 theta_i) cancels)")
        elif flips[j]:
            out.append("Fresnel tie (u1 within float32 rounding of R picks the lobe)")
        elif min(abs(q.wi[j, 2]), abs(q.wo[j, 2]), sampled_z[j]) < GRAZING_COS:
            out.append(f"grazing wi, wo or sampled wo (|cos theta| < {GRAZING_COS:g})")
        elif dense is not None and dense[j]:
            out.append("from the dense side towards the critical angle (Snell's law "
                       "amplifies rounding by eta^2 sin^2 theta_i / cos^2 theta_t)")
        elif d["type"] == "diffuse" and sampled_z[j] < SAMPLED_LOW_COS:
            out.append(f"sampled wo towards the horizon (|cos theta| < {SAMPLED_LOW_COS:g}: "
                       "the cosine warp's z = sqrt(1 - r^2) cancels)")
        elif d["type"] == "dielectric" and 0 < p[j] < RARE_LOBE:
            out.append(f"rare lobe (probability < {RARE_LOBE:g}, formed as 1 - p: "
                       "rounding amplified by (1 - p) / p)")
        else:
            out.append("other")
    return out
