"""Shared parameter handling of the interface models (smooth / rough x dielectric /
conductor, each with an optional thin-film coating): what the exterior, the interior and
the film are, and the C++ Fresnel term they make at a set of wavelengths."""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.optics.metals import metal_ior
from bsdflab.optics.thin_film import FilmLayer
from bsdflab.spectra import Spectrum
from bsdflab.util.args import MAX_EXTINCTION, MAX_IOR, MIN_IOR, flag, ior

MAX_FILM_LAYERS = 32  # the core's fixed scratch size (fresnel_terms.h)
# Relative index of a dielectric interface (interior / exterior): 100 is beyond any pair of
# real media (air to germanium is 4) and keeps Snell's and Fresnel's terms well conditioned.
MAX_IOR_RATIO = 100.0

DEFAULT_EXT_IOR = 1.000277  # air
DEFAULT_INT_IOR = 1.5046    # BK7 at 589 nm (Mitsuba's default)


def parse_film(film) -> tuple[FilmLayer, ...]:
    """A coating: None, a FilmLayer, a dict, or a list of them (top = exterior side first)."""
    if film is None:
        return ()
    items = film if isinstance(film, (list, tuple)) else [film]
    if not isinstance(film, (list, tuple, dict, FilmLayer)):
        raise ValueError(f"film must be a FilmLayer, a dict or a list of them, got {type(film).__name__}")
    if len(items) > MAX_FILM_LAYERS:
        raise ValueError(f"film must have at most {MAX_FILM_LAYERS} layers, got {len(items)}")
    layers = []
    for i, item in enumerate(items):
        if isinstance(item, FilmLayer):
            layers.append(item)
        elif isinstance(item, dict) and {"material", "thickness_nm"} <= set(item):
            layers.append(FilmLayer.from_dict(item) if isinstance(item["material"], dict)
                          else FilmLayer(item["material"], item["thickness_nm"]))
        else:
            raise ValueError(f"film[{i}] must be a FilmLayer or a dict with 'material' and "
                             f"'thickness_nm', got {item!r}")
    return tuple(layers)


def film_to_list(layers: tuple[FilmLayer, ...]) -> list[dict[str, Any]] | None:
    return [layer.to_dict() for layer in layers] or None


class ConductorInterior:
    """Complex index eta + i k of a conductor: a named metal or two spectra."""

    def __init__(self, material: str | None, eta, k):
        if material is not None and (eta is not None or k is not None):
            raise ValueError("give either material or (eta, k), not both")
        if material is None and eta is None and k is None:
            material = "none"
        if material is not None and not isinstance(material, str):
            raise ValueError(f"material must be the name of a metal, got {type(material).__name__}")
        self.material = material
        if material == "none":
            # A perfect mirror, as Mitsuba's default: eta = 0, k = 1 gives R = 1 everywhere.
            self.eta, self.k = Spectrum.constant(0.0), Spectrum.constant(1.0)
        else:
            if material is not None:
                eta, k = metal_ior(material)
            self.eta = Spectrum.coerce(eta if eta is not None else 1.0, "eta", MIN_IOR, MAX_IOR)
            self.k = Spectrum.coerce(k if k is not None else 0.0, "k", 0.0, MAX_EXTINCTION)

    def index(self, wavelengths: np.ndarray) -> np.ndarray:
        return self.eta.at(wavelengths) + 1j * self.k.at(wavelengths)

    def params(self) -> dict[str, Any]:
        if self.material == "none":
            return {}
        if self.material is not None:
            return {"material": self.material}
        return {"eta": self.eta.to_dict(), "k": self.k.to_dict()}


class ConductorParams:
    """What smooth and rough conductors share: their parameters, their Fresnel term and
    their dict form; plus read-only access to the interior (``eta``, ``k``, ``material``)."""

    interior: ConductorInterior

    def _init_conductor(self, material, eta, k, ext_ior, two_sided, film) -> None:
        self.interior = ConductorInterior(material, eta, k)
        self.ext_ior = ext_ior_param(ext_ior)
        self.two_sided = flag("two_sided", two_sided)
        self.film = parse_film(film)

    def _conductor_term(self, wavelengths: np.ndarray):
        return make_term(wavelengths, self.ext_ior, self.film, conductor=self.interior)

    def _conductor_params(self) -> dict[str, Any]:
        p = {**self.interior.params(), "ext_ior": self.ext_ior, "two_sided": self.two_sided}
        if self.film:
            p["film"] = film_to_list(self.film)
        return p

    @property
    def material(self) -> str | None:
        return self.interior.material

    @property
    def eta(self) -> Spectrum:
        return self.interior.eta

    @property
    def k(self) -> Spectrum:
        return self.interior.k


def ext_ior_param(value) -> float:
    return ior("ext_ior", value)


def int_ior_param(value, ext_ior: float) -> float:
    """The interior index: in range itself and relative to the exterior (docs/limits.md)."""
    n = ior("int_ior", value)
    ratio = n / ext_ior
    if not 1.0 / MAX_IOR_RATIO <= ratio <= MAX_IOR_RATIO:
        raise ValueError(f"int_ior / ext_ior must be in [{1 / MAX_IOR_RATIO:g}, {MAX_IOR_RATIO:g}], "
                         f"got {n:g} / {ext_ior:g} = {ratio:g}")
    return n


def make_term(wavelengths: np.ndarray, ext_ior: float, layers: tuple[FilmLayer, ...], *,
              int_ior: float | None = None, conductor: ConductorInterior | None = None):
    """The C++ Fresnel term for these wavelengths: dielectric (int_ior) or conductor."""
    wl = np.asarray(wavelengths, dtype=np.float64)
    if not layers:
        if conductor is not None:
            return _core.ConductorTerm(list(conductor.index(wl)), ext_ior)
        return _core.DielectricTerm(len(wl), int_ior, ext_ior)
    substrate = (conductor.index(wl) if conductor is not None
                 else np.full(len(wl), int_ior, dtype=np.complex128))
    layer_n = [list(np.broadcast_to(layer.material.index(wl), wl.shape)) for layer in layers]
    return _core.FilmTerm(list(wl), ext_ior, layer_n, [layer.thickness_nm for layer in layers],
                          list(substrate), conductor is None)
