"""Which rough-interface (GGX) queries float32 can answer to the target, and how far off
it may be elsewhere.

As in conditioning.py, a query's sensitivity is how far bsdflab's own float64 results
move under float32-sized roundings (``perturbations``), with two additions for
microfacet models:

  * every direction component is perturbed, not only z: the half vector m mixes all
    three, and rough surfaces tilt m far from the normal, where rounding of x and y
    dominates wi . m;
  * a rough dielectric forms 1 - F for transmission (eval, pdf, the lobe probability).
    Where F is near 1 (a microfacet near its critical angle, or light grazing it) the
    relative rounding of 1 - F is amplified by F / (1 - F) (``complement_rounding``).

Quantities of a pair (wi, wo): eval, pdf and ratio = eval / pdf (what a sample's weight
is). Quantities of a sample: those of comparison.SAMPLE_QUANTITIES.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.bsdfs import from_dict
from bsdflab.lobes import Lobe
from bsdflab.optics.fresnel import fresnel_reflectance
from bsdflab.reference.comparison import SAMPLE_QUANTITIES, errors_between, rel_error
from bsdflab.reference.conditioning import GRAZING_COS, INPUT_PERTURBATION, NEAR_CRITICAL_COS2, perturbations
from bsdflab.reference.query_sets import Queries

PAIR_QUANTITIES = ("eval", "pdf", "ratio")
FRESNEL_NEAR_ONE = 0.9   # a transmitted pair with F above this is reported as "F near 1"


@dataclass(frozen=True)
class PairValues:
    eval: np.ndarray   # (N, C)
    pdf: np.ndarray    # (N,)
    ratio: np.ndarray  # (N, C) eval / pdf, 0 where pdf = 0


def pair_values(bsdf, wi: np.ndarray, wo: np.ndarray, channels) -> PairValues:
    """bsdflab's eval, pdf and eval / pdf of the pairs (wi, wo)."""
    value, pdf = bsdf.eval(wi, wo, wavelengths=channels), bsdf.pdf(wi, wo)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(pdf[:, None] > 0, value / pdf[:, None], 0.0)
    return PairValues(value, pdf, ratio)


def microfacet_fresnel(d: dict, wi: np.ndarray, wo: np.ndarray):
    """(F, cos^2 theta_t) at the half vector of each pair (wi, wo) of a rough dielectric,
    as both codes form it (m = wi + eta wo for transmission, turned to +z; F of wi . m
    from wi's side); cos^2 theta_t < 0: total internal reflection on the microfacet."""
    eta = d["int_ior"] / d["ext_ior"]
    reflect = wi[:, 2] * wo[:, 2] > 0
    eta_o = np.where(reflect, 1.0, np.where(wi[:, 2] > 0, eta, 1 / eta))
    m = wi + wo * eta_o[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        m = m / np.linalg.norm(m, axis=1, keepdims=True) * np.where(m[:, 2] < 0, -1.0, 1.0)[:, None]
    c = np.nan_to_num(np.einsum("ij,ij->i", wi, m))
    outside = c > 0
    n_i = np.where(outside, d["ext_ior"], d["int_ior"])
    n_t = np.where(outside, d["int_ior"], d["ext_ior"])
    cos2_t = 1 - (n_i / n_t) ** 2 * (1 - c**2)
    F = fresnel_reflectance(np.clip(np.abs(c), 0.0, 1.0), n_i, n_t).unpolarised
    return F, cos2_t


def complement_rounding(d: dict, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """Relative rounding of 1 - F in float32, for the transmitted pairs of a rough
    dielectric (0 elsewhere, and where F = 1: both codes then give exactly zero)."""
    if d["type"] != "roughdielectric":
        return np.zeros(len(wi))
    F, _ = microfacet_fresnel(d, wi, wo)
    transmitted = (wi[:, 2] * wo[:, 2] < 0) & (F < 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(transmitted, INPUT_PERTURBATION * F / (1 - F), 0.0)


@dataclass(frozen=True)
class RoughSensitivity:
    pairs: list[dict[str, np.ndarray]]  # per set of pairs, per PAIR_QUANTITIES
    sample: dict[str, np.ndarray]       # per SAMPLE_QUANTITIES, of the queries' samples
    flips: np.ndarray                   # a sample's lobe or a pair's validity flips


def rough_sensitivity(d: dict, q: Queries, wo_sets, base_sample: dict,
                      channels) -> RoughSensitivity:
    """Sensitivities of bsdflab's eval / pdf / ratio at the pairs (q.wi, wo) for each wo
    array in ``wo_sets``, and of its sample for (q.wi, q.u1, q.u2) (``base_sample``: the
    unperturbed one, as query_sets.bsdflab_answers gives it)."""
    n, k = len(q.wi), len(wo_sets)
    tiled = Queries(wi=np.tile(q.wi, (k, 1)), wo=np.concatenate(wo_sets),
                    u1=np.tile(q.u1, k), u2=np.tile(q.u2, (k, 1)))
    base = pair_values(from_dict(d), tiled.wi, tiled.wo, channels)
    pair = {key: np.zeros(n * k) for key in PAIR_QUANTITIES}
    sample = {key: np.zeros(n) for key in SAMPLE_QUANTITIES}
    flips = np.zeros(n * k, dtype=bool)
    sample_flips = np.zeros(n, dtype=bool)
    valid = base_sample["lobe"] != 0
    for bsdf_p, t in perturbations(d, tiled, every_component=True):
        r = pair_values(bsdf_p, t.wi, t.wo, channels)
        flips |= (r.pdf > 0) != (base.pdf > 0)
        for key in PAIR_QUANTITIES:
            pair[key] = np.maximum(pair[key], rel_error(getattr(r, key), getattr(base, key)))
        s = bsdf_p.sample(t.wi[:n], t.u1[:n], t.u2[:n], wavelengths=channels)
        same = s.lobe.astype(np.int64) == base_sample["lobe"]
        sample_flips |= ~same
        e = errors_between({"eval": 0, "pdf": 0, "wo": s.wo, "weight": s.weight,
                            "sample_pdf": s.pdf, "eta": s.eta}, base_sample, same & valid)
        for key in SAMPLE_QUANTITIES:
            sample[key] = np.maximum(sample[key], e[key])
    for j, wo in enumerate(wo_sets):
        extra = complement_rounding(d, q.wi, wo)
        for key in ("eval", "pdf"):  # 1 - F cancels in the ratio
            pair[key][j * n:(j + 1) * n] += extra
    refracted = base_sample["lobe"] == int(Lobe.GLOSSY_TRANSMISSION)
    sample["sample_pdf"] += np.where(refracted, complement_rounding(d, q.wi, base_sample["wo"]), 0)
    split = lambda a: [a[j * n:(j + 1) * n] for j in range(k)]
    pairs = [{key: split(pair[key])[j] for key in PAIR_QUANTITIES} for j in range(k)]
    return RoughSensitivity(pairs=pairs, sample=sample,
                            flips=sample_flips | np.any(split(flips), axis=0))


def rough_reasons(d: dict, wi: np.ndarray, wo_sets, idx, flips, steep) -> list[str]:
    """Why float32 cannot resolve each query in ``idx``, judged over all its pairs
    (wi, wo) for the wo arrays in ``wo_sets`` (compared pairs and sampled directions);
    steep: the sample's weight or pdf moves by more than the target between the two
    codes' directions."""
    grazing = np.min([np.abs(wi[:, 2])] + [np.abs(wo[:, 2]) for wo in wo_sets], axis=0)
    near_critical = np.zeros(len(wi), dtype=bool)
    near_one = np.zeros(len(wi), dtype=bool)
    if d["type"] == "roughdielectric":
        for wo in wo_sets:
            F, cos2_t = microfacet_fresnel(d, wi, wo)
            near_critical |= np.abs(cos2_t) < NEAR_CRITICAL_COS2
            near_one |= (wi[:, 2] * wo[:, 2] < 0) & (F > FRESNEL_NEAR_ONE)
    out = []
    for j in idx:
        if near_critical[j]:
            out.append(f"near a microfacet's critical angle (|cos^2 theta_t| < "
                       f"{NEAR_CRITICAL_COS2:g} at the half vector: Fresnel's "
                       "sqrt(cos^2 theta_t) and 1 - F cancel)")
        elif flips[j]:
            out.append("lobe tie or edge of the support (u1 within float32 rounding of F "
                       "picks the lobe, or a pair is valid on one side of a rounding only)")
        elif grazing[j] < GRAZING_COS:
            out.append(f"grazing wi, wo or sampled wo (|cos theta| < {GRAZING_COS:g}: "
                       "G1 and the half vector lose digits)")
        elif steep[j]:
            out.append("sample on a steep lobe (the codes' float32-close sampled directions "
                       "differ in weight or pdf by more than the target)")
        elif near_one[j]:
            out.append(f"light grazing a microfacet (transmission with F > "
                       f"{FRESNEL_NEAR_ONE:g}: 1 - F loses digits)")
        else:
            out.append("steep D(m) or G1 (a value moves by more than the target when the "
                       "directions move by 8 float32 ulps, e.g. near a narrow lobe's peak, or "
                       "Mitsuba's warp frame rounds; see visible_normals.py)")
    return out
