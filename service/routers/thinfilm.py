"""/v1/thinfilm: a thin film's reflectance and transmittance spectra and its reflected
colour vs incidence angle (bsdflab.optics and bsdflab.plots.film_colour)."""
from __future__ import annotations

import numpy as np
from fastapi import APIRouter, Request
from fastapi.responses import Response

from bsdflab.optics import film_reflectance, film_transmittance
from bsdflab.optics.thin_film import FilmLayer, FilmStack
from bsdflab.plots.film_colour import display_exposure, display_srgb, spectral_rgb
from bsdflab.service.bodies import ThreadedBody
from bsdflab.service.deps import HeavyDep, SettingsDep
from bsdflab.service.errors import ERRORS, over_limit
from bsdflab.service.schemas import ThinFilmRequest, ThinFilmResponse
from bsdflab.service.settings import Settings
from bsdflab.util import args as check
from bsdflab.util import ranges

router = APIRouter(prefix="/v1/thinfilm", tags=["thin film"], responses=ERRORS, route_class=ThreadedBody)
DEFAULT_ANGLES = np.arange(0.0, 86.0, 5.0)
# Physical ranges are the library's (bsdflab/util/ranges.py): what bsdflab.optics accepts,
# this route accepts. (Films thicker than the colour strip resolves are refused by it.)
IOR_RANGE = ranges.IOR_RANGE
MAX_THICKNESS_NM = ranges.MAX_FILM_THICKNESS_NM
WAVELENGTH_RANGE_NM = ranges.WAVELENGTH_RANGE_NM
DEFAULT_WAVELENGTHS = np.arange(380.0, 781.0, 5.0)


def _hex(encoded: np.ndarray) -> list[str]:
    levels = np.round(np.clip(encoded, 0.0, 1.0) * 255).astype(int)
    return ["#{:02x}{:02x}{:02x}".format(*row) for row in levels]


@router.post("/spectrum", response_model=ThinFilmResponse, summary="Film spectra and colour vs angle")
async def spectrum(body: ThinFilmRequest, request: Request, settings: SettingsDep, heavy: HeavyDep) -> Response:
    """One film of index ``film_ior`` and ``thickness_nm``, or a stack of ``layers`` (top
    first), between the incident medium and a substrate (real indices): unpolarised R and T
    at each angle and wavelength, and the reflected colour (CIE 1931 2 deg, D65, linear
    sRGB) at each angle, integrated on a grid fine enough for the film's fringes."""
    return await heavy.run(request, _spectrum, body, settings)


def _film(body: ThinFilmRequest):
    """One film as (ext, film, thickness, substrate), or a FilmStack of ``layers``."""
    ext = check.real_scalar("ext_ior", body.ext_ior, *IOR_RANGE)
    substrate = check.real_scalar("substrate_ior", body.substrate_ior, *IOR_RANGE)
    if body.layers is None:
        return (ext, check.real_scalar("film_ior", body.film_ior, *IOR_RANGE),
                check.real_scalar("thickness_nm", body.thickness_nm, 0.0, MAX_THICKNESS_NM), substrate)
    given = {"film_ior", "thickness_nm"} & body.model_fields_set
    if given:
        raise ValueError(f"give the film either as layers or as film_ior and thickness_nm, not both "
                         f"(layers and {', '.join(sorted(given))} were given)")
    layers = [FilmLayer(check.real_scalar(f"layers[{i}].ior", layer.ior, *IOR_RANGE),
                    check.real_scalar(f"layers[{i}].thickness_nm", layer.thickness_nm, 0.0, MAX_THICKNESS_NM))
              for i, layer in enumerate(body.layers)]
    total = sum(layer.thickness_nm for layer in layers)
    if total > MAX_THICKNESS_NM:
        raise ValueError(f"layers: the stack is {total:g} nm thick, more than {MAX_THICKNESS_NM:g} nm")
    return FilmStack(ext, layers, substrate)


def _spectrum(body: ThinFilmRequest, settings: Settings) -> Response:
    angles = DEFAULT_ANGLES if body.angles is None else np.asarray(body.angles, dtype=float)
    wavelengths = DEFAULT_WAVELENGTHS if body.wavelengths is None else np.asarray(body.wavelengths, dtype=float)
    over_limit(settings, "limit_angles", len(angles), "angles")
    over_limit(settings, "limit_wavelengths", len(wavelengths), "wavelengths")
    check.real_array("angles", angles, 0.0, 90.0)
    check.real_array("wavelengths", wavelengths, *WAVELENGTH_RANGE_NM)
    film = _film(body)
    theta = np.radians(angles)[:, None]
    r = film_reflectance(film, wavelengths[None, :], theta)
    t = film_transmittance(film, wavelengths[None, :], theta)
    rgb = spectral_rgb(film, np.radians(angles))
    exposure = display_exposure(rgb, np.radians(angles))
    if not all(np.all(np.isfinite(a)) for a in (r, t, rgb)):
        raise ValueError("the film's reflectance is not finite for these indices and thickness")
    answer = ThinFilmResponse(angles=angles.tolist(), wavelengths=wavelengths.tolist(), reflectance=r.tolist(),
                              transmittance=t.tolist(), rgb=rgb.tolist(), srgb=_hex(display_srgb(rgb, exposure)),
                              exposure=exposure)
    return Response(answer.model_dump_json(), media_type="application/json")
