"""Cross-check bsdflab's BSDFs against Mitsuba 3, query by query.

    python3 -m bsdflab.reference     # reports for the standard materials (__main__.py)

``to_mitsuba`` turns a bsdflab BSDF into a Mitsuba plugin dict; ``compare_bsdf`` draws
random queries (query_sets.py), answers them in both codes from identical float32
inputs and uniforms (eval, pdf, sample), and returns a ``Comparison`` (comparison.py:
the error metric; conditioning.py: which pairs float32 can resolve, and bounds for the
others).

Conventions, checked against Mitsuba 3's source (src/bsdfs/{diffuse,conductor,
dielectric,twosided}.cpp, include/mitsuba/render/fresnel.h):
  * frame and eval: both use the local frame, +z normal, wi and wo pointing away, and
    eval returns f |cos theta_o|; a one-sided BSDF is black unless wi.z > 0 (and wo.z > 0).
  * conductor: ``fresnel_conductor`` is the exact unpolarised (R_s + R_p) / 2 for a
    complex index *relative to the outside*; Mitsuba 3's conductor has no exterior index,
    so bsdflab's absolute (eta, k) go over as (eta, k) / ext_ior.
  * dielectric: reflection iff u1 <= R in both; in radiance mode (BSDFContext's default)
    Mitsuba scales transmitted weights by eta_ti^2 = (n_i / n_t)^2, as bsdflab does;
    sample eta is n_t / n_i in both.
  * two-sided: Mitsuba's ``twosided`` mirrors wi and wo to the upper side, as bsdflab.
  * rough interfaces go over as ``roughconductor`` / ``roughdielectric`` with their
    distribution ('ggx' or 'beckmann'), the same alpha and sample_visible; mitsuba_rough.py
    compares them, since the two codes warp uniforms to visible normals differently. The
    energy-compensated (multiscatter) models have no Mitsuba counterpart.

The helpers the rough comparison shares (``comparison_setup``, ``critical_side``,
``comparison_notes``, ``summarise``) are public here; this module imports nothing of
mitsuba_rough.py.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab.bsdfs import BSDF, from_dict
from bsdflab.optics.metals import metal_ior
from bsdflab.reference.comparison import QUANTITIES, TARGET, Comparison, IllConditionedGroup, errors_between, rel_error
from bsdflab.reference.conditioning import ILL_CONDITIONED, reasons, sensitivity
from bsdflab.reference.mitsuba_calls import mitsuba_answers
from bsdflab.reference.mitsuba_env import mitsuba, variant
from bsdflab.reference.query_sets import bsdflab_answers, draw_queries
from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum, rgb_to_spectrum, spectrum_to_rgb


# -- conversion ----------------------------------------------------------------------------
def _bsdf_dict(bsdf) -> dict[str, Any]:
    if isinstance(bsdf, BSDF):
        return bsdf.to_dict()
    if _is_model(bsdf):  # e.g. a wrapper around a bsdflab BSDF: its dict says what it claims to be
        return from_dict(bsdf.to_dict()).to_dict()
    if isinstance(bsdf, dict):
        return from_dict(bsdf).to_dict()  # validates and fills in defaults
    raise ValueError(f"expected a bsdflab BSDF or its to_dict() form, got {type(bsdf).__name__}")


def _is_model(obj) -> bool:
    return all(callable(getattr(obj, m, None)) for m in ("eval", "pdf", "sample", "to_dict"))


def _check_wavelength(wavelength) -> float | None:
    if wavelength is None:
        return None
    try:
        wl = float(wavelength)
    except (TypeError, ValueError):
        raise ValueError(f"wavelength must be a number of nm or None, got {wavelength!r}") from None
    if not (np.isfinite(wl) and wl > 0):
        raise ValueError(f"wavelength must be finite and > 0 nm, got {wavelength!r}")
    return wl


def _value(spectrum: Spectrum, wavelength: float | None, what: str):
    """Mitsuba's value for a bsdflab spectrum: its float at the wavelength; without one
    (RGB variant), a constant's float or an RGB triple's 'rgb' texture."""
    if wavelength is not None:
        return float(spectrum.at([wavelength])[0])
    d = spectrum.to_dict()
    if d["type"] == "constant":
        return float(d["value"])
    if d["type"] == "rgb":
        return {"type": "rgb", "value": [float(x) for x in d["rgb"]]}
    raise ValueError(f"{what} is a tabulated spectrum; give a wavelength to pass it to "
                     "Mitsuba's RGB variant")


def _conductor_index(d: dict, wavelength: float | None) -> dict[str, float]:
    eta, k = metal_ior(d["material"]) if "material" in d else (
        Spectrum.from_dict(d["eta"]), Spectrum.from_dict(d["k"]))
    out = {}
    for name, spectrum in (("eta", eta), ("k", k)):
        v = _value(spectrum, wavelength, name)
        if isinstance(v, dict):
            raise ValueError(f"a conductor's {name} must be a number for Mitsuba; give a wavelength")
        out[name] = v / d["ext_ior"]  # Mitsuba 3: index relative to the outside medium
    return out


def to_mitsuba(bsdf, wavelength: float | None = None) -> dict[str, Any]:
    """The Mitsuba 3 plugin dict (for ``mi.load_dict``) of a bsdflab BSDF.

    bsdf: a BSDF or its ``to_dict()`` form. wavelength (nm): spectral parameters are
    taken at it as plain floats; None passes constant and RGB parameters as they are and
    rejects tabulated ones. ValueError for a model without a Mitsuba counterpart here.
    """
    d = _bsdf_dict(bsdf)
    wl = _check_wavelength(wavelength)
    kind = d["type"]
    if kind == "measured":  # an RGL .bsdf file: Mitsuba's own reader of the same file
        return {"type": "measured", "filename": str(d["path"])}
    if d.get("film"):
        raise ValueError(f"a thin-film coated {kind} has no Mitsuba counterpart")
    if d.get("multiscatter"):
        raise ValueError(f"an energy-compensated (multiscatter) {kind} has no Mitsuba counterpart")
    if kind == "diffuse":
        plugin = {"type": "diffuse",
                  "reflectance": _value(Spectrum.from_dict(d["reflectance"]), wl, "reflectance")}
    elif kind in ("conductor", "roughconductor"):
        plugin = {"type": kind}  # no eta/k: Mitsuba's material 'none', (0, 1), R = 1
        if "material" in d or "eta" in d:
            plugin.update(_conductor_index(d, wl))
    elif kind in ("dielectric", "roughdielectric"):
        plugin = {"type": kind, "int_ior": float(d["int_ior"]), "ext_ior": float(d["ext_ior"])}
    else:
        raise ValueError(f"no Mitsuba counterpart for bsdflab BSDF type {kind!r} (supported: "
                         "diffuse, conductor, dielectric, roughconductor, roughdielectric)")
    if kind.startswith("rough"):  # separable Smith G, visible-normal sampling
        plugin.update(distribution=d.get("distribution", "ggx"), alpha=float(d["alpha"]),
                      sample_visible=True)
    if d.get("two_sided"):
        plugin = {"type": "twosided", "bsdf": plugin}
    return plugin


# -- comparison ----------------------------------------------------------------------------
def _rgb_round_trip(d: dict, wavelength) -> tuple[float, str]:
    """In sRGB mode, bsdflab lifts an RGB parameter to a spectrum and projects it back,
    while Mitsuba's RGB variant uses it as is: the largest relative difference this makes
    over channels (0 when comparing at a wavelength), and its description."""
    if wavelength is not None:
        return 0.0, ""
    worst, names = 0.0, []
    for name, v in d.items():
        if isinstance(v, dict) and v.get("type") == "rgb":
            rgb = np.asarray(v["rgb"], float)
            back = spectrum_to_rgb(rgb_to_spectrum(rgb, DEFAULT_WAVELENGTHS), DEFAULT_WAVELENGTHS)
            worst = max(worst, float(rel_error(back[None], rgb[None])[0]))
            names.append(name)
    if not names:
        return 0.0, ""
    return worst, (f"{', '.join(names)} RGB -> spectrum (Mallett-Yuksel) -> sRGB round trip, "
                   f"relative {worst:.1e}; added to the target")


def comparison_notes(d: dict) -> tuple[str, ...]:
    if d["type"] in ("conductor", "roughconductor"):
        return (f"Mitsuba's conductor takes the relative index: (eta, k) / ext_ior, "
                f"ext_ior = {d['ext_ior']:g}",)
    if d["type"] in ("dielectric", "roughdielectric"):
        return ("transmission weight (n_i/n_t)^2 in both (radiance mode)",)
    return ()


def critical_side(d: dict) -> tuple[float, int] | None:
    """(eta_ti > 1, side) of the dense side of a refracting interface, else None."""
    if d["type"] not in ("dielectric", "roughdielectric") or d["int_ior"] == d["ext_ior"]:
        return None
    eta = d["int_ior"] / d["ext_ior"]
    return (eta, -1) if eta > 1 else (1 / eta, 1)


def comparison_setup(bsdf, n_pairs, wavelength, target):
    """Checked arguments of a comparison: (BSDF dict, wavelength, target, text of the
    model difference that widened the default target, or '')."""
    d = _bsdf_dict(bsdf)
    wl = _check_wavelength(wavelength)
    if isinstance(n_pairs, bool) or int(n_pairs) != n_pairs or n_pairs < 1:
        raise ValueError(f"n_pairs must be a positive integer, got {n_pairs!r}")
    round_trip, round_trip_text = _rgb_round_trip(d, wl)
    target = TARGET + round_trip if target is None else float(target)
    if not target > 0:
        raise ValueError(f"target must be > 0, got {target!r}")
    return d, wl, target, round_trip_text


def compare_bsdf(bsdf, n_pairs: int = 1000, seed: int = 0, wavelength: float | None = 550.0,
                 target: float | None = None) -> Comparison:
    """Compare bsdflab with Mitsuba 3 on ``n_pairs`` random queries.

    bsdflab is evaluated at ``wavelengths=[wavelength]`` and each of Mitsuba's three RGB
    channels is compared with it; wavelength=None compares bsdflab's sRGB output with
    Mitsuba's RGB instead. target: relative error allowed on well-conditioned pairs;
    default TARGET (1e-5), plus the spectral round trip of RGB parameters in sRGB mode.
    """
    d, wl, target, round_trip_text = comparison_setup(bsdf, n_pairs, wavelength, target)
    # The object itself answers (so a model that differs from its dict, e.g. one injected by
    # bsdflab.validation to prove the check has power, is what gets compared).
    b = bsdf if _is_model(bsdf) else from_dict(d)
    q = draw_queries(int(n_pairs), seed, critical_side(d))
    channels = None if wl is None else [wl]
    ours = bsdflab_answers(b, q, channels)
    theirs = mitsuba_answers(to_mitsuba(d, wl), q)
    same_lobe = ours["lobe"] == theirs["lobe"]
    err = errors_between(ours, theirs, same_lobe & (ours["lobe"] != 0))

    sens, flips = sensitivity(d, q, ours, channels)
    return summarise(
        repr(b), wl, err, sens, flips, lambda idx: reasons(d, q, ours, idx, flips),
        same_lobe=same_lobe, sampled=same_lobe & (ours["lobe"] != 0),
        validity_mismatch=(ours["lobe"] != 0) != (theirs["lobe"] != 0), target=target,
        model_difference=round_trip_text, notes=comparison_notes(d))


def summarise(label: str, wl, err: dict, sens: dict, flips: np.ndarray, why, *,
               same_lobe: np.ndarray, sampled: np.ndarray, validity_mismatch: np.ndarray,
               target: float, model_difference: str, notes: tuple[str, ...],
               quantities: tuple[str, ...] = QUANTITIES) -> Comparison:
    """The ``Comparison`` of per-pair errors ``err`` and float32 sensitivities ``sens``
    (dicts over ``quantities``). flips: pairs whose lobe or validity flips under float32
    roundings; why(idx): the reason of each ill-conditioned pair in idx; same_lobe,
    sampled, validity_mismatch: per pair, the samples' lobes agree / both codes sampled
    the same lobe / exactly one code has a valid answer."""
    well_k = {k: ~flips & (sens[k] <= ILL_CONDITIONED) for k in quantities}
    ill = ~np.all([well_k[k] for k in quantities], axis=0)
    bound = {k: target + sens[k] for k in quantities}

    groups = []
    ill_idx = np.flatnonzero(ill)
    why = why(ill_idx)
    for reason in sorted(set(why)):
        idx = ill_idx[[r == reason for r in why]]
        groups.append(IllConditionedGroup(
            reason=reason, count=len(idx),
            max_error={k: float(err[k][idx].max()) for k in quantities},
            max_error_over_bound=float(max((err[k][idx] / bound[k][idx]).max() for k in quantities)),
            lobe_flips=int(np.sum(~same_lobe[idx] & flips[idx]))))

    return Comparison(
        label=label, reference=f"Mitsuba {mitsuba().__version__} ({variant()})",
        wavelength=wl, n_pairs=len(flips), n_well_conditioned=int(np.sum(~ill)),
        max_error={k: float(err[k][well_k[k]].max(initial=0.0)) for k in quantities},
        n_well={k: int(well_k[k].sum()) for k in quantities},
        n_sampled=int(np.sum(sampled)),
        n_lobe_mismatch=int(np.sum(~same_lobe & ~flips & ~validity_mismatch)),
        n_validity_mismatch=int(np.sum(validity_mismatch & ~flips)),
        n_over_target=int(np.sum(np.any([well_k[k] & (err[k] > target) for k in quantities], axis=0))),
        ill_conditioned=tuple(groups), target=target, model_difference=model_difference,
        notes=notes, quantities=quantities)


# -- the standard set ---------------------------------------------------------------------
def standard_cases() -> list[tuple[str, BSDF, float | None]]:
    """(id, BSDF, wavelength in nm or None for sRGB) of the materials reported on."""
    from bsdflab.bsdfs import Conductor, Dielectric, Diffuse

    return [
        ("diffuse-grey", Diffuse(0.5), 550.0),
        ("diffuse-rgb-srgb", Diffuse([0.8, 0.3, 0.1]), None),
        ("diffuse-rgb-550nm", Diffuse([0.8, 0.3, 0.1]), 550.0),
        ("diffuse-two-sided", Diffuse(0.7, two_sided=True), 550.0),
        ("conductor-Au-450nm", Conductor("Au"), 450.0),
        ("conductor-Au-550nm", Conductor("Au"), 550.0),
        ("conductor-Au-650nm", Conductor("Au"), 650.0),
        ("conductor-Ag", Conductor("Ag"), 550.0),
        ("conductor-Cu", Conductor("Cu"), 550.0),
        ("conductor-Al", Conductor("Al"), 550.0),
        ("conductor-mirror", Conductor(), 550.0),
        ("conductor-custom", Conductor(eta=1.7, k=2.3, ext_ior=1.33), 550.0),
        ("conductor-Cu-two-sided", Conductor("Cu", two_sided=True), 550.0),
        ("dielectric-glass", Dielectric(1.5, 1.0), 550.0),
        ("dielectric-default", Dielectric(), 550.0),
        ("dielectric-int-lt-ext", Dielectric(1.0, 1.33), 550.0),
        ("dielectric-diamond", Dielectric(2.419, 1.000277), 550.0),
    ]
