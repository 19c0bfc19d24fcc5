"""/v1/bsdf: evaluate a model at direction pairs, and its lobe as data or as a picture.

Every route computes on the heavy pool (bsdflab.service.heavy): bounded concurrency, 429
when full, a compute deadline, cancelled when the client leaves; the C++ core releases the
GIL, so the event loop never waits on them. Answers are bounded before computing
(``limit_response_bytes``); ``Accept: application/x-npy`` gives evaluations as a NumPy
array."""
from __future__ import annotations

import io
import json
import os
import tempfile
from typing import Annotated

import numpy as np
from fastapi import APIRouter, HTTPException, Query, Request
from fastapi.responses import Response

from bsdflab import slices as lobe_views
from bsdflab.plots.lobe import lobe_figure
from bsdflab.requests import ModelCache
from bsdflab.service import artefact_refs
from bsdflab.service.bodies import ThreadedBody
from bsdflab.service.deps import HeavyDep, JobsDep, SettingsDep, client_of, model_spec
from bsdflab.service.errors import ERRORS, over_limit
from bsdflab.service.heavy import check_cancelled, evaluate_in_chunks
from bsdflab.service.schemas import EvalRequest, EvalResponse, HemisphereView, LobeRequest, LobeResponse, PlaneView
from bsdflab.service.settings import Settings, limit_variable

MODELS = ModelCache(32, 256 << 20)   # recently asked-for models, their core objects built (create_app sets the bound)
router = APIRouter(prefix="/v1/bsdf", tags=["bsdf"], responses=ERRORS, route_class=ThreadedBody)


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


def _thickness(values: list[float] | None, pairs: int) -> np.ndarray | None:
    """A per-query film thickness: one per pair, or one for all."""
    if values is None:
        return None
    if len(values) not in (1, pairs):
        raise ValueError(f"thickness_nm must have one value or one per pair ({pairs}); got {len(values)}")
    return np.asarray(values, dtype=float)


def _check_answer(settings: Settings, pairs: int, channels: int, stochastic: bool, binary: bool,
                  extra_values: int = 0) -> None:
    """Refuse, before computing, an answer whose estimated size is over the limit: pairs x
    channels (twice with standard errors) at about 24 bytes a number in JSON, 8 in .npy."""
    numbers = pairs * channels * (2 if stochastic else 1) + extra_values
    if binary:
        size = NPY_BYTES * numbers
    else:
        size = JSON_BYTES * (numbers + 6 * pairs)   # wi and wo are echoed in JSON
    limit = settings.limit_response_bytes
    if size > limit:
        hint = "" if binary else "; the binary form (Accept: application/x-npy) is about 3x smaller"
        raise HTTPException(422, f"the answer would be about {size >> 20} MiB ({pairs} pairs x {channels} channels"
                                 f"{' x 2 with standard errors' if stochastic else ''}), more than the limit of "
                                 f"{limit >> 20} MiB ({limit_variable('limit_response_bytes')}){hint}")


def _json_answer(model) -> Response:
    """The answer serialised here, on the heavy thread (an async route's return value would
    be serialised on the event loop, where a large answer would hold up /healthz)."""
    return Response(model.model_dump_json(), media_type="application/json")


def wants_npy(request: Request) -> bool:
    return NPY_TYPE in request.headers.get("accept", "")


def _npy(values: np.ndarray, stderr: np.ndarray | None, channels: list[str]) -> Response:
    array = np.asarray(values, dtype=np.float64) if stderr is None else np.stack([values, stderr]).astype(np.float64)
    buffer = io.BytesIO()
    np.save(buffer, array, allow_pickle=False)
    return Response(buffer.getvalue(), media_type=NPY_TYPE,
                    headers={"X-Shape": ",".join(map(str, array.shape)), "X-Channels": ",".join(channels),
                             "X-Layout": "values" if stderr is None else "values,stderr"})


NPY_TYPE = "application/x-npy"
JSON_BYTES, NPY_BYTES = 24, 8
EVAL_RESPONSES = {200: {"content": {NPY_TYPE: {"schema": {"type": "string", "format": "binary"}}},
                        "description": "JSON, or with `Accept: application/x-npy` a NumPy .npy array of "
                                       "float64: (pairs, channels), or (2, pairs, channels) = values and "
                                       "standard errors for stochastic models; headers X-Shape, X-Channels, "
                                       "X-Layout"}}


@router.post("/eval", response_model=EvalResponse, responses=EVAL_RESPONSES,
             summary="Evaluate a BSDF at direction pairs")
async def evaluate(body: EvalRequest, request: Request, settings: SettingsDep, jobs: JobsDep, heavy: HeavyDep):
    """f(wi, wo) |cos theta_o| (Mitsuba's convention) for every pair, in linear sRGB (D65) or
    at the given wavelengths, with standard errors for stochastic (layered) models. The
    same request always gives the same answer (walks are seeded from seed, wi, wo).
    ``Accept: application/x-npy`` answers a compact NumPy array instead of JSON."""
    binary = wants_npy(request)

    def compute():   # on the heavy pool, after its admission: the store lookups too
        bsdf = MODELS.get(model_spec(body.spec(), jobs, client=client_of(request)))
        wi, wo = _directions(body, settings)
        if body.wavelengths is not None:
            over_limit(settings, "limit_wavelengths", len(body.wavelengths), "wavelengths")
        if len(wi) != len(wo) and 1 not in (len(wi), len(wo)):
            raise ValueError(f"wi and wo must have one length (or length 1); got {len(wi)} and {len(wo)}")
        pairs = max(len(wi), len(wo))
        channels = ["R", "G", "B"] if body.wavelengths is None else [f"{w:g}" for w in body.wavelengths]
        _check_walks(settings, bsdf, pairs, body.samples)
        _check_answer(settings, pairs, len(channels), lobe_views.is_stochastic(bsdf), binary)
        thickness = _thickness(body.thickness_nm, pairs)
        result = evaluate_in_chunks(bsdf, wi, wo, body.wavelengths, body.samples, body.seed, thickness)
        if result.stderr is not None:
            request.app.state.metrics.walks.inc(pairs * (body.samples or bsdf.samples))
        if binary:
            return _npy(result.values, result.stderr, channels)
        wi, wo = np.broadcast_to(wi, (pairs, 3)), np.broadcast_to(wo, (pairs, 3))
        # model_construct: the fields are built here from numpy arrays, validating them again
        # would cost ten times the evaluation of a cheap model (bench/bench_service.py)
        return _json_answer(EvalResponse.model_construct(
            channels=channels, wi=wi.tolist(), wo=wo.tolist(), values=_rows(result.values),
            stderr=_rows(result.stderr), stochastic=result.stderr is not None))

    return await heavy.run(request, compute)


@router.post("/lobe", response_model=LobeResponse, summary="A lobe slice and a hemisphere grid as data")
async def lobe(body: LobeRequest, request: Request, settings: SettingsDep, jobs: JobsDep, heavy: HeavyDep):
    """The plane of incidence (signed outgoing angle, mirror direction at +theta_i) and the
    upper hemisphere seen from above (orthographic x, y), in linear sRGB, for one incidence."""
    def compute():   # on the heavy pool, after its admission: the store lookups too
        bsdf = MODELS.get(model_spec(body.spec(), jobs, client=client_of(request)))
        over_limit(settings, "limit_lobe_resolution", body.points, "points")
        over_limit(settings, "limit_lobe_resolution", body.resolution, "resolution")
        wi = lobe_views.incident(body.theta_i)
        stochastic = lobe_views.is_stochastic(bsdf)
        plane = body.points if body.view in ("plane", "both") else 0
        grid = body.resolution**2 if body.view in ("hemisphere", "both") else 0
        # plane values (+ errors), hemisphere rgb (+ luminance and its error)
        _check_answer(settings, plane, 3, stochastic, False, extra_values=grid * (5 if stochastic else 4))
        out = LobeResponse.model_construct(theta_i=body.theta_i, wi=wi.tolist(),
                                           model=artefact_refs.public(bsdf.to_dict(), jobs.artefact_dir),
                                           stochastic=stochastic, plane=None, hemisphere=None)
        if plane:
            _check_walks(settings, bsdf, body.points, body.samples)
            angles, v = lobe_views.plane_of_incidence(bsdf, body.theta_i, body.points, body.samples, body.seed)
            out.plane = PlaneView.model_construct(angle_deg=angles.tolist(), values=_rows(v.values),
                                                  stderr=_rows(v.stderr))
        check_cancelled()
        if grid:
            _check_walks(settings, bsdf, body.resolution**2, body.samples)
            x, inside, v = lobe_views.hemisphere(bsdf, body.theta_i, body.resolution, body.samples, body.seed)
            out.hemisphere = _hemisphere_view(x, inside, v)
        return _json_answer(out)

    return await heavy.run(request, compute)


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


def _checked_figure(settings: Settings, jobs, spec: dict, theta_i: float, samples: int, seed: int,
                    client=None) -> Response:
    bsdf = MODELS.get(model_spec(spec, jobs, client=client))   # on the heavy pool, after its admission
    _figure_checks(settings, bsdf, theta_i, samples)
    return _figure(bsdf, theta_i, samples, seed)


@router.post("/lobe.png", response_class=Response, responses=PNG, summary="The lobe figure (PNG)")
async def lobe_png(body: LobeRequest, request: Request, settings: SettingsDep, jobs: JobsDep,
                   heavy: HeavyDep) -> Response:
    """The figure of ``bsdflab lobe``: lobe in the plane of incidence, the hemisphere, and
    albedo vs incidence angle with its colour. ``samples`` sets the albedo estimates'
    sample count (default 20000); ``points``, ``resolution`` and ``view`` do not apply."""
    samples = body.samples or FIGURE_SAMPLES
    return await heavy.run(request, _checked_figure, settings, jobs, body.spec(), body.theta_i, samples,
                           body.seed or 0, client_of(request))


@router.get("/lobe.png", response_class=Response, responses=PNG, summary="The lobe figure (PNG), by query")
async def lobe_png_query(request: Request, settings: SettingsDep, jobs: JobsDep, heavy: HeavyDep,
                   preset: Annotated[str | None, Query(min_length=1, description="a preset name")] = None,
                   overrides: Annotated[str | None,
                                        Query(min_length=1, description="the preset's overrides as JSON")] = None,
                   model: Annotated[str | None, Query(min_length=1, description="a BSDF dict as JSON")] = None,
                   theta_i: Annotated[float, Query(description="incidence angle in degrees")] = 30.0,
                   samples: Annotated[int, Query(ge=1, le=1 << 24)] = FIGURE_SAMPLES,
                   seed: Annotated[int, Query(ge=0, lt=1 << 64)] = 0) -> Response:
    """As POST, with the model in the query: ``?preset=xenopeltis&theta_i=45`` or
    ``?model={"type":"diffuse","reflectance":0.5}`` (URL-encoded)."""
    spec = {"preset": preset, "overrides": _json("overrides", overrides), "model": _json("model", model)}
    return await heavy.run(request, _checked_figure, settings, jobs, spec, theta_i, samples, seed,
                          client_of(request))


def _json(name: str, text: str | None):
    if text is None:
        return None
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"{name} is not valid JSON: {e}") from None
