"""Cross-check bsdflab's rough (GGX and Beckmann) interfaces against Mitsuba 3, query by
query.

    python3 -m bsdflab.reference     # reports, rough materials included

``RoughConductor`` / ``RoughDielectric`` go over as Mitsuba's ``roughconductor`` /
``roughdielectric`` (mitsuba_bsdf.to_mitsuba). Both codes warp uniforms to visible
normals differently (visible_normals.py), so identical uniforms give different samples.
For each random query (wi, wo, u1, u2) of query_sets.py (both sides, grazing; near the
critical angle from the dense side of a dielectric, where most microfacets reflect
totally) the checks are:

  1. eval and pdf of the pair (wi, wo): deterministic, so they must agree directly;
  2. each code's own sample, judged by the other code: bsdflab's (wo, weight, pdf) for
     (u1, u2) against Mitsuba's eval(wi, wo) / pdf(wi, wo) and pdf(wi, wo), wo rounded to
     float32 ("weight@bsdflab_wo", "pdf@bsdflab_wo"); Mitsuba's sample for (u1, u2)
     against bsdflab's eval / pdf there ("weight@mitsuba_wo", "pdf@mitsuba_wo");
  3. the samples themselves: bsdflab given the uniforms that reach Mitsuba's disk point
     (visible_normals.bsdflab_uniforms) must draw Mitsuba's direction, lobe, weight, pdf
     and eta (the quantities of the smooth checks).

Errors are relative to Mitsuba's value (comparison.py); which queries float32 cannot
resolve, and their bounds, come from rough_conditioning.py.

Beckmann: Mitsuba 3 evaluates Smith's G1 by a rational approximation (relative error up
to ~0.35 %; Walter et al. 2007, eq. 27) in eval, pdf and the sample weight, while bsdflab
uses the exact Lambda. Mitsuba's answers are converted to the exact G1 per direction
(``exact_g1_factor``: eval by the factors of wi and wo, pdf and sample pdf by wi's, the
sample weight by its wo's) before they are compared; everything else -- D, the warp, the
Fresnel terms, the Jacobians -- is compared as is. The sampled slopes of both codes come
from the same uniforms (u_x along the incident azimuth, u_y across it), which Mitsuba
clamps to [1e-6, 1 - 1e-6].
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from bsdflab.bsdfs import BSDF, from_dict
from bsdflab.oracles.microsurface import smith_lambda
from bsdflab.reference.comparison import QUANTITIES, Comparison, errors_between, rel_error
from bsdflab.reference.conditioning import ILL_CONDITIONED, INPUT_PERTURBATION
from bsdflab.reference.mitsuba_bsdf import comparison_notes, comparison_setup, critical_side, summarise, to_mitsuba
from bsdflab.reference.mitsuba_calls import mitsuba_answers
from bsdflab.reference.query_sets import bsdflab_answers, draw_queries
from bsdflab.reference.rough_conditioning import pair_values, rough_reasons, rough_sensitivity
from bsdflab.reference.visible_normals import bsdflab_uniforms, warp_frame_shift

ROUGH_TYPES = ("roughconductor", "roughdielectric")
CROSS_QUANTITIES = ("weight@bsdflab_wo", "pdf@bsdflab_wo", "weight@mitsuba_wo", "pdf@mitsuba_wo")
ROUGH_QUANTITIES = QUANTITIES + CROSS_QUANTITIES
WARP_NOTE = ("visible-normal warps differ (bsdflab: polar disk; Mitsuba: concentric disk, "
             "first axis flipped): samples compared with bsdflab's uniforms mapped to "
             "Mitsuba's disk point; each code's own samples cross-evaluated by the other")


BECKMANN_WARP_NOTE = ("visible slopes: both codes invert the same CDFs (Heitz & d'Eon 2014) "
                      "from the same uniforms (Mitsuba's clamp to [1e-6, 1 - 1e-6] applied); "
                      "each code's own samples cross-evaluated by the other")
BECKMANN_NOTE = ("Mitsuba's Beckmann G1 is a rational approximation (<= 0.35 %): its eval, "
                 "pdf and weights are converted to the exact Smith G1 per direction")


def mitsuba_g1(alpha: float, w: np.ndarray) -> np.ndarray:
    """Mitsuba 3's Beckmann G1 of directions w (N, 3) (the rational fit of Walter et al.
    2007, eq. 27, in a = 1 / (alpha tan theta); 1 at and beyond a = 1.6)."""
    sin = np.hypot(w[:, 0], w[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.abs(w[:, 2]) / (alpha * sin)
        fit = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    return np.where((sin == 0) | (a >= 1.6), 1.0, fit)


def exact_g1_factor(d: dict, w: np.ndarray) -> np.ndarray:
    """Exact Smith G1 over Mitsuba's G1 for directions w (N, 3): 1 for GGX (both exact)."""
    if d.get("distribution", "ggx") != "beckmann":
        return np.ones(len(w))
    up = w * np.where(w[:, 2] < 0, -1.0, 1.0)[:, None]
    exact = 1.0 / (1.0 + smith_lambda("beckmann", d["alpha"], up))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(exact > 0, exact / mitsuba_g1(d["alpha"], up), 1.0)


def exact_g1_answers(d: dict, answers: dict, q) -> dict:
    """Mitsuba's answers to queries q with its G1 replaced by the exact one (module doc)."""
    ci, co, cs = (exact_g1_factor(d, w) for w in (q.wi, q.wo, answers["wo"]))
    return {**answers, "eval": answers["eval"] * (ci * co)[:, None], "pdf": answers["pdf"] * ci,
            "weight": answers["weight"] * cs[:, None], "sample_pdf": answers["sample_pdf"] * ci}


def _ratio(value: np.ndarray, pdf: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(pdf[:, None] > 0, value / pdf[:, None], 0.0)


def compare_rough(bsdf, n_pairs: int = 1000, seed: int = 0, wavelength: float | None = 550.0,
                  target: float | None = None) -> Comparison:
    """Compare a bsdflab rough interface with Mitsuba 3 on ``n_pairs`` random queries
    (arguments as mitsuba_bsdf.compare_bsdf); the record's quantities are
    ROUGH_QUANTITIES (module doc)."""
    d, wl, target, model_difference = comparison_setup(bsdf, n_pairs, wavelength, target)
    if d["type"] not in ROUGH_TYPES:
        raise ValueError(f"compare_rough compares {', '.join(ROUGH_TYPES)}, got {d['type']!r}")
    b, plugin = from_dict(d), to_mitsuba(d, wl)
    channels = None if wl is None else [wl]
    q = draw_queries(int(n_pairs), seed, critical_side(d))
    mapped = replace(q, u2=bsdflab_uniforms(d, q.u2, q.wi))

    ours = bsdflab_answers(b, mapped, channels)   # eval / pdf of (wi, wo); mapped samples
    theirs = exact_g1_answers(d, mitsuba_answers(plugin, q), q)
    own = b.sample(q.wi, q.u1, q.u2, wavelengths=channels)  # bsdflab's own warp
    ok = {"ours": ours["lobe"] != 0, "theirs": theirs["lobe"] != 0, "own": own.lobe != 0}
    # Sampled directions; the pair's wo where there is no sample (results there unused).
    fill = lambda valid, wo: np.where(valid[:, None], wo, q.wo)
    wo = {"ours": fill(ok["ours"], ours["wo"]), "theirs": fill(ok["theirs"], theirs["wo"]),
          "own": fill(ok["own"], own.wo),
          "own32": fill(ok["own"], own.wo.astype(np.float32).astype(np.float64))}
    own_q = replace(q, wo=wo["own32"])
    at_own = exact_g1_answers(d, mitsuba_answers(plugin, own_q), own_q)
    at = {k: pair_values(b, q.wi, v, channels) for k, v in wo.items()}  # bsdflab's eval / pdf
    sens = rough_sensitivity(d, mapped, (q.wo, wo["own32"], wo["theirs"]), ours, channels)

    same_lobe = ours["lobe"] == theirs["lobe"]
    sampled = same_lobe & ok["ours"]
    err = errors_between(ours, theirs, sampled)
    mitsuba_ratio = _ratio(at_own["eval"], at_own["pdf"])
    cross = {
        "weight@bsdflab_wo": (ok["own"], rel_error(own.weight, mitsuba_ratio)),
        "pdf@bsdflab_wo": (ok["own"], rel_error(own.pdf, at_own["pdf"])),
        "weight@mitsuba_wo": (ok["theirs"], rel_error(at["theirs"].ratio, theirs["weight"])),
        "pdf@mitsuba_wo": (ok["theirs"], rel_error(at["theirs"].pdf, theirs["sample_pdf"])),
    }
    err.update({key: np.where(valid, e, 0.0) for key, (valid, e) in cross.items()})

    # Bounds. Terms that compare bsdflab with itself compare eval / pdf at two directions,
    # never its sample with its eval / pdf, so that they cannot hide a sampling error.
    # Mitsuba sees bsdflab's own samples rounded to float32:
    rounded = {"ratio": rel_error(at["own32"].ratio, at["own"].ratio),
               "pdf": rel_error(at["own32"].pdf, at["own"].pdf)}
    # The mapped samples' directions differ within float32, also through Mitsuba's warp
    # frame (visible_normals.warp_frame_shift); on a steep lobe that moves weight and pdf
    # by bsdflab's own change between the two directions, and evaluating at Mitsuba's
    # float32 direction rounds.
    moved = {"ratio": np.where(sampled, rel_error(at["ours"].ratio, at["theirs"].ratio), 0.0),
             "pdf": np.where(sampled, rel_error(at["ours"].pdf, at["theirs"].pdf), 0.0)}
    there = sens.pairs[2]
    s = {"eval": sens.pairs[0]["eval"], "pdf": sens.pairs[0]["pdf"], **sens.sample,
         "weight@bsdflab_wo": sens.pairs[1]["ratio"] + rounded["ratio"],
         "pdf@bsdflab_wo": sens.pairs[1]["pdf"] + rounded["pdf"],
         "weight@mitsuba_wo": there["ratio"], "pdf@mitsuba_wo": there["pdf"]}
    s["weight"] = s["weight"] + moved["ratio"] + np.where(sampled, there["ratio"], 0.0)
    s["sample_pdf"] = s["sample_pdf"] + moved["pdf"] + np.where(sampled, there["pdf"], 0.0)
    s["direction"] = s["direction"] + warp_frame_shift(
        d, q.wi, mapped.u1, mapped.u2, ours["wo"], ours["lobe"], INPUT_PERTURBATION, channels)

    validity_mismatch = ((ok["ours"] != ok["theirs"]) | (ok["own"] & ~(at_own["pdf"] > 0))
                         | (ok["theirs"] & ~(at["theirs"].pdf > 0)))
    steep = np.any([v > ILL_CONDITIONED for v in moved.values()], axis=0)
    all_wo = (q.wo, wo["own32"], wo["theirs"], wo["ours"])
    return summarise(
        repr(b), wl, err, s, sens.flips,
        lambda idx: rough_reasons(d, q.wi, all_wo, idx, sens.flips, steep),
        same_lobe=same_lobe, sampled=sampled,
        validity_mismatch=validity_mismatch, target=target, model_difference=model_difference,
        notes=comparison_notes(d) + ((BECKMANN_WARP_NOTE, BECKMANN_NOTE)
                                     if d.get("distribution") == "beckmann" else (WARP_NOTE,)),
        quantities=ROUGH_QUANTITIES)


def rough_cases() -> list[tuple[str, BSDF, float | None]]:
    """(id, BSDF, wavelength in nm) of the rough materials reported on."""
    from bsdflab.bsdfs import RoughConductor, RoughDielectric

    cases = []
    for a in (0.05, 0.3, 0.8):
        cases += [
            (f"roughconductor-Au-a{a:g}", RoughConductor(a, material="Au"), 550.0),
            (f"roughconductor-Cu-a{a:g}", RoughConductor(a, material="Cu"), 650.0),
            (f"roughconductor-custom-a{a:g}", RoughConductor(a, eta=1.7, k=2.3, ext_ior=1.33), 550.0),
            (f"roughdielectric-glass-a{a:g}", RoughDielectric(a, 1.5, 1.0), 550.0),
            (f"roughdielectric-int-lt-ext-a{a:g}", RoughDielectric(a, 1.0, 1.33), 550.0),
        ]
    for a in (0.05, 0.3, 0.8):
        cases += [
            (f"roughconductor-Au-beckmann-a{a:g}",
             RoughConductor(a, material="Au", distribution="beckmann"), 550.0),
            (f"roughdielectric-glass-beckmann-a{a:g}",
             RoughDielectric(a, 1.5, 1.0, distribution="beckmann"), 550.0),
            (f"roughdielectric-int-lt-ext-beckmann-a{a:g}",
             RoughDielectric(a, 1.0, 1.33, distribution="beckmann"), 550.0),
        ]
    return cases + [
        ("roughconductor-mirror-a0.3", RoughConductor(0.3), 550.0),
        ("roughconductor-Cu-two-sided-a0.3", RoughConductor(0.3, "Cu", two_sided=True), 550.0),
        ("roughdielectric-diamond-a0.3", RoughDielectric(0.3, 2.419, 1.000277), 550.0),
    ]
