"""What of a bsdflab material a single-film standard can carry, read from its dict form.

The targets (OpenPBR, glTF, Blender's Principled BSDF, USD through OpenPBR) describe one
surface: a dielectric specular layer with at most one thin film, GGX roughness, over a
diffuse body colour. From a bsdflab model this module takes

* the top interface: outside and inside indices, GGX alpha, its film (one layer);
* a first body colour: the diffuse base's albedo seen through the pigment slabs, each crossed
  twice at normal incidence (exp(-2 sigma_a t)), averaged spectrally into linear sRGB (the
  export replaces it with the fit of ``bsdflab.export.body``);

and lists what is dropped (spectral absorption of the slabs, their scattering, deeper
interfaces). Units: indices are real; thicknesses in nm; alpha is GGX alpha (the targets'
roughness parameter is sqrt(alpha)).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bsdflab.util import args as check

SPREAD = 0.15   # the snake's per-scale film-thickness spread (+-15 %, the paper's scale texture)


@dataclass
class ExportMaterial:
    """A single-film surface: the part of a bsdflab material a target can represent."""

    ext_ior: float
    int_ior: float
    film_ior: float | None           # None: no film
    film_thickness_nm: float
    alpha: float                     # GGX alpha; 0 for a smooth interface
    body_rgb: tuple[float, float, float]
    dropped: list[str] = field(default_factory=list)
    stack: tuple[tuple[float, float], ...] = ()   # (index, thickness nm) of a multilayer film, when substituted

    @property
    def has_film(self) -> bool:
        return self.film_ior is not None and self.film_thickness_nm > 0.0

    def to_dict(self) -> dict:
        return {"ext_ior": self.ext_ior, "int_ior": self.int_ior, "film_ior": self.film_ior,
                "film_thickness_nm": self.film_thickness_nm, "alpha": self.alpha,
                "body_rgb": list(self.body_rgb), "dropped": list(self.dropped),
                "stack": [list(layer) for layer in self.stack]}


VISIBLE_NM = np.arange(380.0, 781.0, 5.0)
DESIGN_NM = 550.0   # where a dispersive index is read when the dispersion is dropped


def _scalar_ior(value, name: str, dropped: list[str] | None = None) -> float:
    """One real index: a number, or a dispersion dict (constant, Cauchy, tabulated) that is
    constant over the visible (a Cauchy with B = C = 0, a fit's film), or else read at
    DESIGN_NM with the dispersion listed as dropped. An absorbing index (k > 0) is refused."""
    from bsdflab.optics.dispersion import as_dispersion

    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    if not isinstance(value, dict):
        raise ValueError(f"{name}: an index must be a number or a dispersion dict, got {type(value).__name__}")
    try:
        z = as_dispersion(value, name).index(VISIBLE_NM)
    except ValueError as e:
        raise ValueError(f"{name}: {e}") from None
    if np.max(z.imag) > 0:
        raise ValueError(f"{name}: an absorbing index (k up to {np.max(z.imag):.3g}) cannot be exported "
                         "(the targets take one real index)")
    n = z.real
    if np.ptp(n) <= 1e-9 * np.max(n):
        return float(n[0])
    at = float(np.interp(DESIGN_NM, VISIBLE_NM, n))
    if dropped is not None:
        dropped.append(f"{name}: dispersion (n {np.min(n):.4f}-{np.max(n):.4f} over 380-780 nm): the targets take "
                       f"one real index, exported n({DESIGN_NM:g} nm) = {at:.4f}")
    return at


def _top(d: dict, dropped: list[str], substitute: bool = False):
    kind = d.get("type")
    if kind not in ("dielectric", "roughdielectric"):
        raise ValueError(f"nothing exportable: the top interface is a {kind!r}; the targets take a "
                         "dielectric (optionally rough, optionally with one thin film)")
    alpha = float(d.get("alpha", 0.0)) if kind == "roughdielectric" else 0.0
    if kind == "roughdielectric" and d.get("alpha_v") not in (None, d.get("alpha")):
        dropped.append("anisotropic roughness (alpha_v): the export is isotropic")
    film = d.get("film") or []
    stack = ()
    if len(film) > 1:
        if not substitute:
            raise ValueError(f"a film stack of {len(film)} layers is beyond the targets, which take one "
                             "thin film: export one film, or ask for the single film that looks most like the stack "
                             "(substitute=True; on the command line, bsdflab export --substitute)")
        stack = tuple((_scalar_ior(f["material"], "film material", dropped), float(f["thickness_nm"])) for f in film)
        dropped.append(f"the {len(film)}-layer film stack: replaced by the single film that looks most like "
                       "it (fitted against the stack's exact reflectance)")
        # the fit's start: the densest layer's index at the stack's optical thickness
        n_film = max(n for n, _ in stack)
        t = sum(n * t for n, t in stack) / n_film
    else:
        n_film, t = (None, 0.0) if not film else (_scalar_ior(film[0]["material"], "film material", dropped),
                                                  float(film[0]["thickness_nm"]))
    return (_scalar_ior(d.get("ext_ior", 1.000277), "ext_ior", dropped),
            _scalar_ior(d.get("int_ior", 1.5046), "int_ior", dropped), n_film, t, alpha, stack)


def _slab_transmittance(slabs: list[dict], wl: np.ndarray, dropped: list[str]) -> np.ndarray:
    from bsdflab.spectra import Spectrum

    T = np.ones_like(wl)
    for i, s in enumerate(slabs):
        t_um = float(s.get("thickness_um", 0.0))
        if t_um <= 0.0:
            continue
        sigma_a = Spectrum.coerce(s.get("sigma_a", 0.0), "sigma_a").at(wl)
        T = T * np.exp(-2.0 * sigma_a * t_um)
        dropped.append(f"slab {i}: spectral absorption ({t_um:g} um) and scattering (sigma_s "
                       f"{s.get('sigma_s', 0)}) folded into the fitted base colour; their angular "
                       "dependence beyond (1 - F) is not represented")
    return T


def export_material(model, substitute: bool = False) -> ExportMaterial:
    """The exportable part of a BSDF (object or dict); ValueError when nothing is exportable
    or the film is a stack beyond the targets (unless ``substitute``: then the stack is kept
    for the fit, which finds the best single film)."""
    from bsdflab.spectra import Spectrum, spectrum_to_rgb

    d = model if isinstance(model, dict) else model.to_dict()
    dropped: list[str] = []
    kind = d.get("type")
    if kind == "layered":
        interfaces = d.get("interfaces") or []
        if len(interfaces) > 1:
            dropped.append(f"{len(interfaces) - 1} interface(s) below the top: not represented")
        ext, intr, n_film, t, alpha, stack = _top(interfaces[0], dropped, substitute)
        base = d.get("base") or {}
        if base.get("type") != "diffuse":
            raise ValueError(f"nothing exportable below the top: the base is a {base.get('type')!r}; "
                             "the targets take a diffuse body colour")
        wl = np.arange(380.0, 781.0, 5.0)
        albedo = Spectrum.coerce(base.get("reflectance", 0.5), "reflectance").at(wl)
        spectrum = albedo * _slab_transmittance(d.get("slabs") or [], wl, dropped)
        body = np.clip(spectrum_to_rgb(spectrum, wl), 0.0, 1.0)
    elif kind in ("dielectric", "roughdielectric"):
        ext, intr, n_film, t, alpha, stack = _top(d, dropped, substitute)
        body = np.zeros(3)
        dropped.append("transmission: the export is an opaque surface (black body colour)")
    else:
        raise ValueError(f"nothing exportable: a {kind!r} has no dielectric thin-film surface "
                         "(export a layered model with a dielectric top, or a dielectric)")
    if n_film is None:
        dropped.append("no thin film: the export's film weight is 0")
    check.real_scalar("film thickness", t, 0.0, 1e5)
    return ExportMaterial(ext, intr, n_film, t, alpha, tuple(float(x) for x in body), dropped, stack)
