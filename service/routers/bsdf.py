"""/v1/bsdf: evaluate a model at direction pairs, and its lobe as data or as a picture.

Synchronous routes (plain ``def``): FastAPI runs them on its thread pool, and the C++ core
releases the GIL, so the event loop never waits on them."""
from __future__ import annotations

import json
import os
import tempfile
from typing import Annotated

import numpy as np
from fastapi import APIRouter, Query
from fastapi.responses import Response

from bsdflab import slices as lobe_views
from bsdflab.requests import ModelCache
from bsdflab.plots.lobe import lobe_figure

from bsdflab.service.deps import KEY, SettingsDep
from bsdflab.service.errors import ERRORS, KEY_ERRORS, over_limit
from bsdflab.service.schemas import (EvalRequest, EvalResponse, HemisphereView, LobeRequest, LobeResponse, PlaneView)
from bsdflab.service.settings import Settings

MODELS = ModelCache(32)   # recently asked-for models, their core objects built
router = APIRouter(prefix="/v1/bsdf", tags=["bsdf"], dependencies=[KEY], responses={**ERRORS, **KEY_ERRORS})


def _rows(a: np.ndarray | None) -> list | None:
    """A (N, C) array as nested lists; non-finite entries (never expected from the core)
    become null rather than invalid JSON."""
    if a is None:
        return None
    a = np.asarray(a, dtype=np.float64)
    if np.all(np.isfinite(a)):
        return a.tolist()
    return [[float(v) if np.isfinite(v) else None for v in row] for row in a]


def _check_walks(settings: Settings, bsdf, pairs: int, samples: int | None) -> None:
    if not lobe_views.is_stochastic(bsdf):
        return
    walks = samples if samples is not None else bsdf.samples
    over_limit(settings, "limit_samples", walks, "walks per direction pair (samples)")
    over_limit(settings, "limit_walks", pairs * walks, "direction pairs x walks")


def _directions(body: EvalRequest, settings: Settings) -> tuple[np.ndarray, np.ndarray]:
    vectors = body.wi is not None or body.wo is not None
    angles = body.theta_i is not None or body.theta_o is not None or body.phi is not None
    if vectors == angles:
        raise ValueError("give directions either as vectors (wi and wo) or as angles "
                         "(theta_i, theta_o and optionally phi, in degrees)")
    lists = [x for x in (body.wi, body.wo, body.theta_i, body.theta_o, body.phi) if x is not None]
    over_limit(settings, "limit_directions", max(len(x) for x in lists), "directions per request")
    if vectors:
        if body.wi is None or body.wo is None:
            raise ValueError("give both wi and wo")
        return np.asarray(body.wi, dtype=float), np.asarray(body.wo, dtype=float)
    if body.theta_i is None or body.theta_o is None:
        raise ValueError("give both theta_i and theta_o (degrees); phi defaults to 180, the mirror side")
    lengths = {len(x) for x in lists} - {1}
    if len(lengths) > 1:
        raise ValueError(f"theta_i, theta_o and phi must have one length (or length 1); got {sorted(lengths)}")
    return lobe_views.directions_from_angles(body.theta_i, body.theta_o, body.phi if body.phi is not None else [180.0])


@router.post("/eval", response_model=EvalResponse, summary="Evaluate a BSDF at direction pairs")
def evaluate(body: EvalRequest, settings: SettingsDep) -> EvalResponse:
    """f(wi, wo) |cos theta_o| (Mitsuba's convention) for every pair, in linear sRGB (D65) or
    at the given wavelengths, with standard errors for stochastic (layered) models. The
    same request always gives the same answer (walks are seeded from seed, wi, wo)."""
    bsdf = MODELS.get(body.spec())
    wi, wo = _directions(body, settings)
    if body.wavelengths is not None:
        over_limit(settings, "limit_wavelengths", len(body.wavelengths), "wavelengths")
    if len(wi) != len(wo) and 1 not in (len(wi), len(wo)):
        raise ValueError(f"wi and wo must have one length (or length 1); got {len(wi)} and {len(wo)}")
    pairs = max(len(wi), len(wo))
    _check_walks(settings, bsdf, pairs, body.samples)
    result = lobe_views.evaluate(bsdf, wi, wo, body.wavelengths, body.samples, body.seed)
    channels = ["R", "G", "B"] if body.wavelengths is None else [f"{w:g}" for w in body.wavelengths]
    wi, wo = np.broadcast_to(wi, (pairs, 3)), np.broadcast_to(wo, (pairs, 3))
    # model_construct: the fields are built here from numpy arrays, validating them again
    # would cost ten times the evaluation of a cheap model (bench/bench_service.py)
    return EvalResponse.model_construct(channels=channels, wi=wi.tolist(), wo=wo.tolist(),
                                        values=_rows(result.values), stderr=_rows(result.stderr),
                                        stochastic=result.stderr is not None)


@router.post("/lobe", response_model=LobeResponse, summary="A lobe slice and a hemisphere grid as data")
def lobe(body: LobeRequest, settings: SettingsDep) -> LobeResponse:
    """The plane of incidence (signed outgoing angle, mirror direction at +theta_i) and the
    upper hemisphere seen from above (orthographic x, y), in linear sRGB, for one incidence."""
    bsdf = MODELS.get(body.spec())
    over_limit(settings, "limit_lobe_resolution", body.points, "points")
    over_limit(settings, "limit_lobe_resolution", body.resolution, "resolution")
    wi = lobe_views.incident(body.theta_i)
    out = LobeResponse.model_construct(theta_i=body.theta_i, wi=wi.tolist(), model=bsdf.to_dict(),
                                       stochastic=lobe_views.is_stochastic(bsdf), plane=None, hemisphere=None)
    if body.view in ("plane", "both"):
        _check_walks(settings, bsdf, body.points, body.samples)
        angles, v = lobe_views.plane_of_incidence(bsdf, body.theta_i, body.points, body.samples, body.seed)
        out.plane = PlaneView.model_construct(angle_deg=angles.tolist(), values=_rows(v.values),
                                              stderr=_rows(v.stderr))
    if body.view in ("hemisphere", "both"):
        _check_walks(settings, bsdf, body.resolution**2, body.samples)
        x, inside, v = lobe_views.hemisphere(bsdf, body.theta_i, body.resolution, body.samples, body.seed)
        out.hemisphere = _hemisphere_view(x, inside, v)
    return out


def _hemisphere_view(x: np.ndarray, inside: np.ndarray, v: lobe_views.Values) -> HemisphereView:
    def grid(values: np.ndarray | None):
        """Values of the inside cells back on the (R, R) grid, null outside the disc."""
        if values is None:
            return None
        out: list[list] = [[None] * inside.shape[1] for _ in range(inside.shape[0])]
        rows = _rows(values.reshape(len(values), -1))
        for (r, c), value in zip(np.argwhere(inside), rows):
            out[r][c] = value if values.ndim > 1 else value[0]
        return out

    lum = lobe_views.luminance(v.values)
    lum_err = None if v.stderr is None else lobe_views.luminance(v.stderr)
    return HemisphereView.model_construct(x=x.tolist(), y=x.tolist(), rgb=grid(v.values), luminance=grid(lum),
                                          luminance_stderr=grid(lum_err))


def _figure(bsdf, theta_i: float, samples: int, seed: int) -> Response:
    fd, path = tempfile.mkstemp(suffix=".png")
    os.close(fd)
    try:
        lobe_figure(bsdf, np.radians(theta_i), path, samples=samples, seed=seed)
        with open(path, "rb") as f:
            return Response(f.read(), media_type="image/png")
    finally:
        os.unlink(path)


PNG = {200: {"content": {"image/png": {}}, "description": "the lobe figure (PNG)"}}
FIGURE_SAMPLES = 20_000


def _figure_checks(settings: Settings, bsdf, theta_i: float, samples: int) -> None:
    lobe_views.incident(theta_i)   # validates the angle
    over_limit(settings, "limit_walks", samples, "figure samples")
    if lobe_views.is_stochastic(bsdf):   # the hemisphere panel's grid, 64 walks a pixel
        over_limit(settings, "limit_walks", 48 * 48 * 64, "figure walks")


@router.post("/lobe.png", response_class=Response, responses=PNG, summary="The lobe figure (PNG)")
def lobe_png(body: LobeRequest, settings: SettingsDep) -> Response:
    """The figure of ``bsdflab lobe``: lobe in the plane of incidence, the hemisphere, and
    albedo vs incidence angle with its colour. ``samples`` sets the albedo estimates'
    sample count (default 20000); ``points``, ``resolution`` and ``view`` do not apply."""
    bsdf = MODELS.get(body.spec())
    samples = body.samples or FIGURE_SAMPLES
    _figure_checks(settings, bsdf, body.theta_i, samples)
    return _figure(bsdf, body.theta_i, samples, body.seed or 0)


@router.get("/lobe.png", response_class=Response, responses=PNG, summary="The lobe figure (PNG), by query")
def lobe_png_query(settings: SettingsDep,
                   preset: Annotated[str | None, Query(description="a preset name")] = None,
                   overrides: Annotated[str | None, Query(description="the preset's overrides as JSON")] = None,
                   model: Annotated[str | None, Query(description="a BSDF dict as JSON")] = None,
                   theta_i: Annotated[float, Query(description="incidence angle in degrees")] = 30.0,
                   samples: Annotated[int, Query(ge=1, le=1 << 24)] = FIGURE_SAMPLES,
                   seed: Annotated[int, Query(ge=0, lt=1 << 64)] = 0) -> Response:
    """As POST, with the model in the query: ``?preset=xenopeltis&theta_i=45`` or
    ``?model={"type":"diffuse","reflectance":0.5}`` (URL-encoded)."""
    spec = {"preset": preset, "overrides": _json("overrides", overrides), "model": _json("model", model)}
    bsdf = MODELS.get(spec)
    _figure_checks(settings, bsdf, theta_i, samples)
    return _figure(bsdf, theta_i, samples, seed)


def _json(name: str, text: str | None):
    if text is None:
        return None
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"{name} is not valid JSON: {e}") from None
