"""Fit the diffuse body colour to the layered model's scattered reflectance, by CIEDE2000.

What is matched: the hemispherical albedo of the light that enters the material and comes
back out (the layered model's reflectance without the top interface's own reflection,
``Layered.estimate(..., scattered_only=True)``), integrated over the outgoing hemisphere,
per RGB channel, at a few incidence angles. Integration: a midpoint grid uniform in
cos theta_o and phi_o (exact for a Lambertian lobe), E(theta_i) = 2 pi mean(f |cos theta_o|),
with the walks' standard error carried along.

The targets (OpenPBR, the Principled BSDF, glTF) put their dielectric specular layer over a
diffuse base by albedo scaling: the body shows through what the specular layer leaves,
E_target(theta_i) = C (1 - F(theta_i)), F the target's own specular reflectance at its
fitted parameters. The body colour C (linear sRGB, in [0, 1]) minimises the mean Delta E00
between E_target and the layered model's E over the angles (start: least squares per
channel, then Nelder-Mead).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BODY_ANGLES_DEG = np.array([0.0, 30.0, 50.0, 70.0])
GRID = 16          # cos theta_o cells; 2 GRID in phi
SAMPLES = 16       # walks per direction pair


@dataclass
class BodyFit:
    rgb: np.ndarray            # (3,) fitted body colour, linear sRGB
    angles_deg: np.ndarray     # (A,)
    albedo: np.ndarray         # (A, 3) the layered model's scattered albedo
    stderr: np.ndarray         # (A, 3) its standard error
    target: np.ndarray         # (A, 3) C (1 - F) at the fit
    delta_e: np.ndarray        # (A,)

    def summary(self) -> dict:
        return {"angles_deg": self.angles_deg.tolist(), "albedo_exact": np.round(self.albedo, 6).tolist(),
                "albedo_export": np.round(self.target, 6).tolist(), "delta_e00": np.round(self.delta_e, 4).tolist(),
                "median": float(np.median(self.delta_e)), "max": float(self.delta_e.max())}


def _hemisphere(n: int = GRID) -> np.ndarray:
    c = (np.arange(n) + 0.5) / n
    phi = 2.0 * np.pi * (np.arange(2 * n) + 0.5) / (2 * n)
    s = np.sqrt(1.0 - c**2)
    return np.stack([s[:, None] * np.cos(phi), s[:, None] * np.sin(phi), c[:, None] * np.ones_like(phi)],
                    axis=-1).reshape(-1, 3)


def scattered_albedo(layered, angles_deg=BODY_ANGLES_DEG, grid: int = GRID, samples: int = SAMPLES,
                     seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(albedo, stderr), each (A, 3): the scattered (non-top-reflection) hemispherical albedo
    of a ``Layered`` model at each incidence angle (deg), linear sRGB."""
    wo = _hemisphere(grid)
    vals, errs = [], []
    for k, deg in enumerate(np.asarray(angles_deg, float)):
        t = np.radians(deg)
        wi = np.tile([np.sin(t), 0.0, np.cos(t)], (len(wo), 1))
        # error_walks=0: the sum's error gets its degrees of freedom from the many pairs, not
        # from one pair's heavy-tailed walks (docs/coverage.md)
        e = layered.estimate(wi, wo, samples=samples, seed=seed + k, scattered_only=True, error_walks=0)
        vals.append(2.0 * np.pi * e.value.mean(axis=0))
        errs.append(2.0 * np.pi * np.sqrt((e.stderr**2).sum(axis=0)) / len(wo))
    return np.array(vals), np.array(errs)


def fit_body(albedo: np.ndarray, specular: np.ndarray, angles_deg=BODY_ANGLES_DEG,
             stderr: np.ndarray | None = None) -> BodyFit:
    """The body colour C whose C (1 - specular) best matches ``albedo`` (both (A, 3)) by
    mean Delta E00 over the angles."""
    from scipy.optimize import minimize

    from bsdflab.reference.approximations.study import delta_e00

    a, through = np.asarray(albedo, float), 1.0 - np.clip(np.asarray(specular, float), 0.0, 1.0)
    c0 = np.clip((a * through).sum(0) / np.maximum((through**2).sum(0), 1e-12), 0.0, 1.0)

    def cost(c):
        return float(np.mean(delta_e00(np.clip(c, 0.0, 1.0) * through, a)))

    res = minimize(cost, c0, method="Nelder-Mead",
                   options={"xatol": 1e-6, "fatol": 1e-6, "initial_simplex": np.vstack([c0, c0 + np.diag(
                       np.maximum(0.05 * c0, 1e-4))])})
    c = np.clip(res.x, 0.0, 1.0) if res.fun <= cost(c0) else c0
    c = np.round(c, 6)
    return BodyFit(c, np.asarray(angles_deg, float), a, np.zeros_like(a) if stderr is None else stderr,
                   c * through, delta_e00(c * through, a))


def fit_material_body(model, target, film_fit) -> BodyFit | None:
    """The body colour fit of a layered ``model`` (object or dict) for ``target`` at the
    film fit's parameters; None when the model has no body (a bare dielectric: black)."""
    from bsdflab.bsdfs.base import from_dict
    from bsdflab.export.fit import target_rgb

    layered = from_dict(model) if isinstance(model, dict) else model
    if layered.type_name != "layered":
        return None
    albedo, err = scattered_albedo(layered)
    spec = target_rgb(target, film_fit.thickness_nm, film_fit.film_ior, film_fit.base_ior,
                      BODY_ANGLES_DEG, [1.0])[:, 0]
    return fit_body(albedo, spec, BODY_ANGLES_DEG, err)
