"""Write RGL ``.bsdf`` materials (Dupuy & Jakob 2018) from bsdflab tables and models.

The file stores an isotropic BSDF as a warp plus values on the warp's unit square
(docs/measured.md). We build each part from the source BSDF ``f``:

1. **NDF.** The retro-reflection of a microfacet surface is f(m, m) = F G1 D(m) / (4 cos^2)
   with G1(m) = cos(theta_m) / sigma(m), so D(m) ~ Y(f(m, m)) cos(theta_m) sigma[D](m) up
   to F: the paper's fixed point, found by power iteration (``_estimate_ndf``); mixed with a little of the cosine NDF
   (``ndf_floor``) so every half vector stays reachable; normalised to integrate(D cos) = 1.
2. **sigma(wi)** = integral of D(m) max(0, wi . m) dm, by quadrature of the stored NDF.
3. **VNDF** per incident angle: D(m) max(0, wi . m) times the Jacobian of
   u -> m, 2 pi^2 u sin(theta_m): a density in u-space (the reader normalises it).
4. **Values** on the VNDF's square: at node s, u_m = VNDF(s), wo = reflect(wi, m) and the
   value is f(wi, wo) cos(theta_o) * 4 sigma(wi) / D(m) (``jacobian`` = 1), zero where wo
   is below the surface. The reader multiplies D / (4 sigma) back, so at every node it
   returns the source exactly (to float32).
5. **Luminance**: the values' luminance (plus a small floor), so sampling the luminance
   warp then the VNDF draws wo with density ~ Y(f cos(theta_o)).

The error is measured, not assumed: the reader's answer (``RGLReference``, the reader's
arithmetic) is compared with the source at the centre of every cell of the (theta_i, s)
grid -- where multilinear interpolation errs most for smooth functions (error <= h^2/8
max|f''|, attained mid-cell) -- and at random direction pairs, both uniform and drawn
from the file's own sampler. ``ExportReport.bound`` is ``BOUND_SAFETY`` times the largest
error seen; tests check fresh random pairs against it.
"""
from __future__ import annotations

import json
import math
import os
import time
from dataclasses import asdict, dataclass

import numpy as np

from bsdflab.measured.marginal import Marginal2D
from bsdflab.measured.rgl_file import RGLData, check_fields
from bsdflab.measured.rgl_reference import RGLReference, u2phi, u2theta
from bsdflab.measured.tensor_file import write_tensor_file
from bsdflab.spectra import srgb_weights
from bsdflab.util import args as check

PI = math.pi
BOUND_SAFETY = 2.0
# theta_i nodes run from 0 to this (rad); beyond it the reader holds the last node.
THETA_I_MAX = math.radians(89.0)
# Retro-reflection and source probes stay this far (rad) above the horizon.
GRAZING = math.radians(0.5)
# The NDF's power iteration (Dupuy & Jakob 2018): at most this many steps, stopping when
# no node moves by more than NDF_TOLERANCE of the peak.
NDF_ITERATIONS = 30
NDF_TOLERANCE = 1e-4
# The stored warp's cosine floor by default (rgl_from_bsdf's vndf_floor): 0, the paper's VNDF;
# 0.5 halves the grazing error of rough gold but not of every source (docs/measured.md).
VNDF_FLOOR = 0.0


@dataclass(frozen=True)
class ExportReport:
    """The resampling error of an export, in units of the source's f * cos(theta_o) (1/sr
    times cosine): the largest absolute per-channel difference seen (``max_abs_error``),
    the peak source value (``peak``), their ratio, the RMS difference, the bound the writer
    reports (``bound`` = BOUND_SAFETY * max_abs_error) and the points it looked at."""

    max_abs_error: float
    peak: float
    relative_error: float
    rms_error: float
    bound: float
    points: int
    seconds: float
    bytes: int = 0
    max_abs_error_60: float = 0.0  # the same, with both directions within 60 deg of the normal


    def summary(self) -> str:
        return (f"resampling error: max {self.max_abs_error:.3g} (peak f cos {self.peak:.3g}, "
                f"relative {self.relative_error:.2%}; {self.max_abs_error_60:.3g} with both "
                f"directions within 60 deg), rms {self.rms_error:.3g}, reported bound "
                f"{self.bound:.3g} over {self.points} points")


def rgl_from_bsdf(bsdf, wavelengths=None, *, n_theta_i: int = 16, resolution: int = 32,
                  ndf_resolution: int = 64, ndf_floor: float = 0.05, ndf_iterations: int = NDF_ITERATIONS,
                  vndf_floor: float = VNDF_FLOOR, error_points: int = 20000,
                  seed: int = 0, source: dict | None = None) -> tuple[RGLData, ExportReport]:
    """An RGL material resampled from an isotropic BSDF's reflection.

    Parameters
    ----------
    bsdf : bsdflab BSDF
        The source (a model or a ``TableBSDF``); only reflection (both directions above the
        surface) is exported -- the RGL format has no transmission.
    wavelengths : array of nm, optional
        None: an RGB file (``rgb`` field; the source's own channels for a table). Otherwise
        a spectral file at these wavelengths (``spectra`` + ``wavelengths``).
    n_theta_i : int in [2, 90]
        Incident elevations, uniform over [0, 89] degrees.
    resolution : int in [4, 256]
        Nodes per side of the value and luminance grids.
    ndf_resolution : int in [4, 1024]
        Nodes of the NDF, sigma and VNDF along theta (the VNDF has resolution nodes in phi).
    ndf_floor : float in (0, 1)
        Weight of the cosine NDF mixed into the estimated one.
    ndf_iterations : int in [1, 100]
        Most steps of the NDF's power iteration (it stops earlier once converged); 1 is
        the estimate without the shadowing correction, D ~ f(m, m) cos^2(theta_m).
    vndf_floor : float in [0, 10]
        Weight of D(m) cos(theta_m) added to the stored warp's D(m) max(0, wi . m): 0 is the
        paper's VNDF; the default resolves grazing incidence better (any warp is a valid
        file: the reader divides by the same density it inverts).
    error_points : int in [0, 10**7]
        Random direction pairs for the error report (plus every cell centre).
    source : dict, optional
        What to say about the source in the file's description (JSON).
    """
    started = time.perf_counter()
    n_theta_i = check.integer("n_theta_i", n_theta_i, 2, 90)
    resolution = check.integer("resolution", resolution, 4, 256)
    ndf_resolution = check.integer("ndf_resolution", ndf_resolution, 4, 1024)
    ndf_floor = check.real_scalar("ndf_floor", ndf_floor, 0.0, 1.0, lo_open=True, hi_open=True)
    ndf_iterations = check.integer("ndf_iterations", ndf_iterations, 1, 100)
    vndf_floor = check.real_scalar("vndf_floor", vndf_floor, 0.0, 10.0)
    error_points = check.integer("error_points", error_points, 0, 10**7)
    f, lum_w, channel_wl = _source(bsdf, wavelengths)

    u_ndf = np.linspace(0.0, 1.0, ndf_resolution)
    ndf_row = _estimate_ndf(f, lum_w, u_ndf, ndf_floor, ndf_iterations)
    ndf = np.tile(ndf_row, (2, 1)).astype(np.float32)
    ndf_warp = Marginal2D(ndf, normalize=False)
    sigma_row = _sigma(ndf_warp, u2theta(u_ndf))
    sigma = np.tile(sigma_row, (2, 1)).astype(np.float32)
    sigma_warp = Marginal2D(sigma, normalize=False)

    theta_i = np.linspace(0.0, THETA_I_MAX, n_theta_i).astype(np.float32)
    phi_i = np.zeros(1, dtype=np.float32)
    vndf = np.stack([_vndf_slice(ndf_warp, float(t), ndf_resolution, resolution, vndf_floor) for t in theta_i])[None]
    vndf = vndf.astype(np.float32)
    vndf_warp = Marginal2D(vndf, (phi_i, theta_i))

    # Values at every node of every theta_i slice, in one batch of source evaluations.
    s = _grid(resolution)
    nodes = np.repeat(theta_i.astype(np.float64), len(s))
    s_all = np.tile(s, (n_theta_i, 1))
    wi, wo, u_m, u_wi = _directions(vndf_warp, s_all, nodes)
    value = np.zeros((len(s_all), len(lum_w)))
    up = wo[:, 2] > 0
    value[up] = f(wi[up], wo[up])
    value *= (4.0 * sigma_warp.eval(u_wi) / ndf_warp.eval(u_m))[:, None]
    values = value.reshape(n_theta_i, resolution, resolution, -1).transpose(0, 3, 1, 2)[None]
    lum = np.maximum(np.einsum("ptcyx,c->ptyx", values, lum_w), 0.0)
    lum += 1e-2 * lum.mean(axis=(2, 3), keepdims=True) + 1e-12
    values = values.astype(np.float32)

    header = {"format": "RGL .bsdf (Dupuy & Jakob 2018), written by bsdflab", "source": source or {},
              "channels": "RGB (linear sRGB, D65)" if channel_wl is None else "spectral, nm",
              "grid": {"n_theta_i": n_theta_i, "resolution": resolution, "ndf_resolution": ndf_resolution,
                       "ndf_floor": ndf_floor, "ndf_iterations": ndf_iterations, "vndf_floor": vndf_floor,
                       "theta_i_max_deg": math.degrees(THETA_I_MAX)},
              "reflection_only": True}
    fields = {"description": json.dumps(header, sort_keys=True), "jacobian": np.array([1], dtype=np.uint8),
              "theta_i": theta_i, "phi_i": phi_i, "ndf": ndf, "sigma": sigma, "vndf": vndf,
              "luminance": lum.astype(np.float32)}
    if channel_wl is None:
        fields["rgb"] = values
    else:
        fields["spectra"] = np.maximum(values, 0.0)
        fields["wavelengths"] = np.asarray(channel_wl, dtype=np.float32)
    data = check_fields({k: (np.frombuffer(v.encode(), np.uint8) if isinstance(v, str) else v)
                         for k, v in fields.items()}, name="the exported material")
    report = measure_error(data, f, theta_i, seed=seed, points=error_points)
    report = ExportReport(**{**asdict(report), "seconds": time.perf_counter() - started})
    header["error"] = asdict(report)
    data = RGLData(**{**data.__dict__, "description": json.dumps(header, sort_keys=True)})
    return data, report


def write_rgl(path, data: RGLData) -> int:
    """Write ``data`` to ``path`` (atomically); returns the file size in bytes."""
    write_tensor_file(path, data.fields())
    return os.path.getsize(path)


RGL_PARTS = ("reflection",)  # what the RGL format carries of a table's parts (lobes)


def export_table(table, out, *, wavelengths=None, parts=RGL_PARTS, **options) -> ExportReport:
    """Write the RGL file ``out`` from a bsdflab table (a path or ``TableBSDF``).

    The table's own channels are kept: RGB tables give an RGB file, spectral tables a
    spectral file at the table's wavelengths. ``parts``: the table parts to write; the RGL
    format carries reflection of light from above only, so any other part (transmission,
    and a two-sided table's reflection_below and transmission_below) raises ValueError; a
    table's other parts are left out of the file (its description lists them).
    ``options`` go to ``rgl_from_bsdf``."""
    from bsdflab.tables import TableBSDF
    from bsdflab.tables.channels import channel_wavelengths

    parts = (parts,) if isinstance(parts, str) else tuple(parts)
    refused = [p for p in parts if p not in RGL_PARTS]
    if refused or not parts:
        raise ValueError(f"the RGL format carries only {', '.join(RGL_PARTS)} (light from above, reflected); "
                         f"it cannot carry {', '.join(map(str, refused)) or 'an empty list of parts'}")
    t = table if isinstance(table, TableBSDF) else TableBSDF(table)
    own = channel_wavelengths(t.table.channels)
    if wavelengths is not None:
        raise ValueError("wavelengths: a table is exported at its own channels; pass None")
    source = {"kind": "bsdflab table", "model": t.table.model, "file": os.path.basename(t.path or ""),
              "parts": list(RGL_PARTS), "parts_left_out": [p for p in t.table.lobes if p not in RGL_PARTS]}
    if t.path:
        from bsdflab.tables.file_format import read_attributes

        source["table_content_hash"] = read_attributes(t.path).get("bsdflab.content_hash")
    data, report = rgl_from_bsdf(t, own, source=source, **options)
    size = write_rgl(out, data)
    return ExportReport(**{**asdict(report), "bytes": size})


def export_model(bsdf, out, wavelengths=None, **options) -> ExportReport:
    """Write the RGL file ``out`` resampled directly from a bsdflab model."""
    data, report = rgl_from_bsdf(bsdf, wavelengths, source={"kind": "bsdflab model", "model": bsdf.to_dict()},
                                 **options)
    size = write_rgl(out, data)
    return ExportReport(**{**asdict(report), "bytes": size})


# -- the parts ---------------------------------------------------------------------------
def _source(bsdf, wavelengths):
    """(f(wi, wo) -> f cos(theta_o) (N, C), luminance weights (C,), wavelengths or None)."""
    from bsdflab.tables import TableBSDF
    from bsdflab.tables.channels import LUMINANCE_RGB

    if isinstance(bsdf, TableBSDF):
        wl = None if wavelengths is None else np.asarray(wavelengths, float)
        call = lambda a, b: bsdf.eval(a, b)
    else:
        wl = None if wavelengths is None else check.real_array("wavelengths", wavelengths, 0.0, lo_open=True, ndim=1)
        call = lambda a, b: bsdf.eval(a, b, wavelengths=wl)
    if wl is None:
        return call, LUMINANCE_RGB, None
    weights = np.maximum(LUMINANCE_RGB @ srgb_weights(wl), 0.0)
    if weights.sum() <= 0:  # no visible channel: weigh all alike
        weights = np.ones(len(wl))
    return call, weights / weights.sum(), wl


def _estimate_ndf(f, lum_w, u, floor, iterations: int = NDF_ITERATIONS):
    """D(theta_m) at the nodes u from the retro-reflection, by the paper's power iteration.

    A microfacet surface reflects f(m, m) = F G1(m) D(m) / (4 cos^2 theta_m) back along m,
    with Smith's G1(m) = cos theta_m / sigma(m) (Heitz 2014), so D ~ f(m, m) cos(theta_m)
    sigma[D](m): D is the fixed point of D -> f cos sigma[D] (normalised), an eigenvector
    found by power iteration from sigma = cos (the smooth-surface guess). F is ignored."""
    theta = np.minimum(u2theta(u), PI / 2 - GRAZING)
    m = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    brdf = np.maximum(f(m, m) @ lum_w, 0.0) / m[:, 2]     # Y(f(m, m)), 1/sr (f returns f cos)
    sigma = m[:, 2]
    d = np.full_like(u, 1 / PI)
    for _ in range(iterations):
        new = brdf * m[:, 2] * sigma
        total = _cos_integral(new, u)
        if not (total > 0 and np.isfinite(total)):
            new = np.full_like(u, 1 / PI)
            break
        new = new / total
        done = np.max(np.abs(new - d)) <= NDF_TOLERANCE * np.max(new)
        d = new
        if done:
            break
        sigma = _sigma_of(d, u, u2theta(u))
    return (1 - floor) * d + floor / PI


def _cos_integral(d, u):
    """2 pi integral of D(theta) cos sin dtheta for D linear in u (fine midpoint rule)."""
    uu = (np.arange(4096) + 0.5) / 4096
    t = u2theta(uu)
    return 2 * PI * np.sum(np.interp(uu, u, d) * np.cos(t) * np.sin(t) * PI * uu) / len(uu)


def _sigma(ndf_warp, theta_i):
    """sigma(theta_i) = integral of D(m) max(0, wi . m) dm for the stored (bilinear) NDF."""
    nu = 1024
    uu = (np.arange(nu) + 0.5) / nu
    return _sigma_of(ndf_warp.eval(np.stack([uu, np.full(nu, 0.5)], axis=1)), uu, theta_i)


def _sigma_of(d, u, theta_i):
    """sigma(theta_i) for an isotropic D given at nodes u (linear in u between them),
    midpoint rule in (u, phi) with dm = sin(theta) dtheta dphi."""
    nu, nphi = 1024, 128
    uu = (np.arange(nu) + 0.5) / nu
    ph = (np.arange(nphi) + 0.5) / nphi * 2 * PI
    tm = u2theta(uu)
    weight = np.interp(uu, u, d) * np.sin(tm) * PI * uu / nu * (2 * PI / nphi)
    cos = (np.cos(theta_i)[:, None, None] * np.cos(tm)[None, :, None]
           + np.sin(theta_i)[:, None, None] * np.sin(tm)[None, :, None] * np.cos(ph)[None, None, :])
    return np.maximum(np.einsum("tup,u->t", np.maximum(cos, 0.0), weight), 1e-12)


def _vndf_slice(ndf_warp, theta_i, nx, ny, floor=0.0):
    """The warp's density in u-space at one incident elevation: D(m) (max(0, wi . m) +
    floor cos theta_m) times the Jacobian of u -> m. floor = 0 is the VNDF; a floor keeps
    area for half vectors near the pole at grazing incidence, where wi . m -> 0 squeezes
    them into the first cell while f cos theta_o is largest there (docs/measured.md)."""
    ux, uy = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
    tm, pm = u2theta(ux), u2phi(uy)
    cos = np.cos(theta_i) * np.cos(tm) + np.sin(theta_i) * np.sin(tm) * np.cos(pm)
    d = ndf_warp.eval(np.stack([ux.ravel(), uy.ravel()], axis=1)).reshape(ux.shape)
    return d * (np.maximum(cos, 0.0) + floor * np.cos(tm)) * 2 * PI * PI * ux * np.sin(tm)


def _grid(n):
    """The (n*n, 2) nodes of the unit square, x fastest (the file's row-major order)."""
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    return np.stack([x.ravel(), y.ravel()], axis=1)


def _directions(vndf_warp, s, theta_i):
    """wi (azimuth 0), wo, u_m and u_wi for points s of the VNDF square at elevations theta_i."""
    params = (np.zeros(len(s)), theta_i)
    u_m, _ = vndf_warp.sample(s, params)
    tm, pm = u2theta(u_m[:, 0]), u2phi(u_m[:, 1])
    m = np.stack([np.cos(pm) * np.sin(tm), np.sin(pm) * np.sin(tm), np.cos(tm)], axis=1)
    ti = np.minimum(theta_i, PI / 2 - GRAZING)
    wi = np.stack([np.sin(ti), np.zeros_like(ti), np.cos(ti)], axis=1)
    wo = 2 * np.sum(m * wi, axis=1, keepdims=True) * m - wi
    u_wi = np.stack([np.sqrt(theta_i * 2 / PI), np.full(len(s), 0.5)], axis=1)
    return wi, wo, u_m, u_wi


def measure_error(data: RGLData, f, theta_i, seed: int = 0, points: int = 20000) -> ExportReport:
    """The reader's error against the source ``f`` at cell centres and random pairs."""
    ref = RGLReference(data)
    n = data.values.shape[-1]
    centres = (np.stack(np.meshgrid(np.arange(n - 1), np.arange(n - 1)), -1).reshape(-1, 2) + 0.5) / (n - 1)
    mids = 0.5 * (theta_i[1:].astype(float) + theta_i[:-1].astype(float))
    s = np.tile(centres, (len(mids), 1))
    wi, wo, _, _ = _directions(ref.vndf, s, np.repeat(mids, len(centres)))
    rng = np.random.default_rng(seed)
    wi_r, wo_r = random_pairs(ref, points, rng)
    wi, wo = np.concatenate([wi, wi_r]), np.concatenate([wo, wo_r])
    keep = (wo[:, 2] > math.sin(GRAZING)) & (wi[:, 2] > math.sin(GRAZING))
    wi, wo = wi[keep], wo[keep]
    a, b = ref.eval(wi, wo), f(wi, wo)
    err = np.abs(a - b)
    worst = float(err.max()) if err.size else 0.0
    peak = float(np.abs(b).max()) if b.size else 0.0
    inner = (wi[:, 2] >= 0.5) & (wo[:, 2] >= 0.5)
    return ExportReport(max_abs_error=worst, peak=peak, relative_error=worst / peak if peak > 0 else 0.0,
                        rms_error=float(np.sqrt(np.mean(err ** 2))) if err.size else 0.0,
                        bound=BOUND_SAFETY * worst, points=len(wi), seconds=0.0,
                        max_abs_error_60=float(err[inner].max()) if inner.any() else 0.0)


def random_pairs(ref: RGLReference, n: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """n direction pairs above the surface: half with wo uniform on the hemisphere, half
    drawn from the file's own sampler (so the peaks are visited)."""
    wi = _uniform_hemisphere(rng, n)
    wo = _uniform_hemisphere(rng, n)
    half = n // 2
    if half:
        drawn, _, pdf = ref.sample(wi[:half], rng.random((half, 2)))
        ok = pdf > 0
        wo[:half][ok] = drawn[ok]
    return wi, wo


def _uniform_hemisphere(rng, n):
    z = rng.random(n)
    phi = rng.random(n) * 2 * PI
    r = np.sqrt(np.maximum(1 - z * z, 0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
