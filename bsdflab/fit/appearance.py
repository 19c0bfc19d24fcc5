"""The appearance posterior: what the parameter uncertainty means for colour.

For posterior draws and for the posterior-mean material, the forward model gives the
specular reflectance spectrum at each viewing angle (380-780 nm, 5 nm); colour-science's
CIE 1931 2° observer under D65 turns it into linear sRGB (bsdflab.spectra.srgb_weights),
XYZ and CIELAB (D65 white), and CIEDE2000 (``colour.delta_E``, "CIE 2000") measures each
draw's difference from the posterior-mean material, per angle.

The full model (rough top, scattering slab) has no mirror beam: its appearance is the gloss
(the reflectance factor pi f at the specular direction, per angle) and the body colour
(CIE 45°:0° geometry: source at 45°, detector along the normal), both from the
adding-doubling solver, so roughness and sigma_s move them as they move the rendered
material. A solve costs seconds, so the draws are not solved one by one: ``full_appearance``
solves the posterior mean and a central-difference stencil (+-h along each free parameter,
h = half its posterior sd) and expands log(pi f) to second order (diagonal) around the mean.
The gloss colour is compared at the mean's luminance (each angle's XYZ divided by the mean's
Y there, so the mean's L* is 100 and a 20 % brighter gloss reads as Delta L* ~ 7).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsdflab.fit.config import ModelSettings
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.forward import ForwardModel
from bsdflab.fit.parameters import ALL_NAMES, FORWARD_NAMES
from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights
from bsdflab.spectra.colour_weights import rgb_colourspace
from bsdflab.util.progress import stop_if_cancelled

_FORWARD_COLS = [ALL_NAMES.index(n) for n in FORWARD_NAMES]


@dataclass
class AppearancePosterior:
    angles_deg: np.ndarray
    rgb: np.ndarray        # (draws, angles, 3) linear sRGB of the specular reflection
    rgb_mean: np.ndarray   # (angles, 3) of the posterior-mean material
    delta_e: np.ndarray    # (draws, angles) CIEDE2000 to the posterior-mean material
    body_delta_e: np.ndarray | None = None   # (draws,) the full model's 45°:0° body colour
    body_rgb_mean: np.ndarray | None = None

    def interval(self, level: float = 0.9) -> dict[str, np.ndarray]:
        """Per angle: median, central ``level`` interval and the ``level`` quantile (the
        "known to within Delta E00 <= x" bound)."""
        lo, hi = (1 - level) / 2, 1 - (1 - level) / 2
        q = np.quantile(self.delta_e, [0.5, lo, hi, level], axis=0)
        return {"median": q[0], "low": q[1], "high": q[2], "bound": q[3]}


def specular_spectra(full: np.ndarray, angles_deg, thickness_nodes: int, angle_nodes: int) -> np.ndarray:
    """Specular reflectance (P, angles, wavelengths) for full parameter vectors (P, 11)."""
    wl = np.asarray(DEFAULT_WAVELENGTHS)
    a = np.asarray(angles_deg, float)
    grid_a, grid_w = np.meshgrid(a, wl, indexing="ij")
    n = grid_a.size
    ds = Dataset(np.full(n, GEOMETRIES.index("specular")), grid_a.ravel(), np.full(n, np.nan),
                 grid_w.ravel(), np.zeros(n), np.ones(n))
    model = ForwardModel(ds, thickness_nodes, angle_nodes)
    return model.evaluate(np.atleast_2d(full)[:, _FORWARD_COLS]).reshape(-1, len(a), len(wl))


def lab_of(rgb: np.ndarray) -> np.ndarray:
    import colour

    cs = rgb_colourspace()
    xyz = rgb @ np.asarray(cs.matrix_RGB_to_XYZ).T
    return colour.XYZ_to_Lab(xyz, illuminant=cs.whitepoint)


def appearance_posterior(draws_full: np.ndarray, mean_full: np.ndarray, angles_deg,
                         thickness_nodes: int, angle_nodes: int) -> AppearancePosterior:
    import colour

    spectra = specular_spectra(np.vstack([mean_full[None, :], draws_full]), angles_deg,
                               thickness_nodes, angle_nodes)
    rgb = spectra @ srgb_weights(DEFAULT_WAVELENGTHS).T
    lab = lab_of(rgb)
    de = colour.delta_E(lab[1:], lab[:1], method="CIE 2000")
    return AppearancePosterior(np.asarray(angles_deg, float), rgb[1:], rgb[0], de)


FULL_WAVELENGTHS_NM = np.arange(400.0, 701.0, 20.0)   # the solver's colour grid (seconds per solve)
BODY_GEOMETRY_DEG = (45.0, 0.0)                        # CIE 45°:0°


def appearance_rows(angles_deg) -> Dataset:
    """brdf rows: the specular direction at each angle, then the 45°:0° body geometry, at
    FULL_WAVELENGTHS_NM."""
    wl = FULL_WAVELENGTHS_NM
    a_in = np.concatenate([np.asarray(angles_deg, float), [BODY_GEOMETRY_DEG[0]]])
    a_out = np.concatenate([np.asarray(angles_deg, float), [BODY_GEOMETRY_DEG[1]]])
    n = len(a_in) * len(wl)
    return Dataset(np.full(n, GEOMETRIES.index("brdf")), np.repeat(a_in, len(wl)), np.repeat(a_out, len(wl)),
                   np.tile(wl, len(a_in)), np.ones(n), np.ones(n), [], np.zeros(n))


def full_appearance(draws_full: np.ndarray, mean_full: np.ndarray, free: tuple[str, ...], angles_deg,
                    model: ModelSettings, progress: bool = False) -> AppearancePosterior:
    """The full model's gloss (per angle) and body colour posterior, by a second-order
    expansion of the solver's log(pi f) around the posterior mean (module docstring)."""
    from bsdflab.fit.full_forward import SolverForwardModel
    from bsdflab.fit.parameters import in_domain

    draws_full = np.atleast_2d(draws_full)
    cols = [ALL_NAMES.index(n) for n in free if n != "noise_scale"]
    sd = np.std(draws_full[:, cols], axis=0) if cols else np.zeros(0)
    h = np.where(sd > 0, 0.5 * sd, 1e-6 * np.maximum(np.abs(mean_full[cols]), 1.0))
    points = [mean_full]
    for j, c in enumerate(cols):
        for sign in (1.0, -1.0):
            v = mean_full.copy()
            v[c] += sign * h[j]
            if not in_domain(ALL_NAMES[c], v[c]):   # one-sided at the domain's edge: mirror the step
                v[c] = mean_full[c] - sign * h[j]
            points.append(v)
    solver = SolverForwardModel(appearance_rows(angles_deg), model)
    logs = []
    for v in _bar(points, progress, "appearance solves"):
        logs.append(np.log(np.maximum(solver.evaluate(v), 1e-12)))
    logs = np.array(logs)
    y0 = logs[0]
    dx = draws_full[:, cols] - mean_full[cols]
    out = np.repeat(y0[None, :], len(draws_full), axis=0)
    for j in range(len(cols)):
        plus, minus = logs[1 + 2 * j], logs[2 + 2 * j]
        sign = np.sign(points[1 + 2 * j][cols[j]] - mean_full[cols[j]]) or 1.0
        if np.sign(points[2 + 2 * j][cols[j]] - mean_full[cols[j]]) == sign:   # both steps on one side
            minus = 2 * y0 - plus
        d1 = sign * (plus - minus) / (2 * h[j])
        d2 = (plus - 2 * y0 + minus) / h[j] ** 2
        out += dx[:, j:j + 1] * d1[None, :] + 0.5 * dx[:, j:j + 1] ** 2 * d2[None, :]
    return full_colour(np.exp(np.vstack([y0[None, :], out])), angles_deg)


def full_colour(values: np.ndarray, angles_deg) -> AppearancePosterior:
    """The appearance posterior from pi f at ``appearance_rows`` (1 + draws, rows): row 0 is
    the posterior mean."""
    import colour

    spectra = values.reshape(len(values), -1, len(FULL_WAVELENGTHS_NM))
    rgb = spectra @ srgb_weights(FULL_WAVELENGTHS_NM).T    # (1 + draws, angles + 1, 3)
    cs = rgb_colourspace()
    xyz = rgb @ np.asarray(cs.matrix_RGB_to_XYZ).T
    gloss = xyz[:, :-1] / xyz[:1, :-1, 1:2]                # the mean's Y = 1 at every angle
    lab_g = colour.XYZ_to_Lab(gloss, illuminant=cs.whitepoint)
    lab_b = colour.XYZ_to_Lab(xyz[:, -1], illuminant=cs.whitepoint)
    return AppearancePosterior(np.asarray(angles_deg, float), rgb[1:, :-1], rgb[0, :-1],
                               colour.delta_E(lab_g[1:], lab_g[:1], method="CIE 2000"),
                               colour.delta_E(lab_b[1:], lab_b[:1], method="CIE 2000"), rgb[0, -1])


def _bar(items, show: bool, desc: str):
    if show:
        from tqdm import tqdm

        items = tqdm(items, desc=desc, unit="solve", leave=False)
    for item in items:
        stop_if_cancelled(desc)
        yield item
