"""Direction pairs by kind and the z-scores of a PFMC estimate against the solver's value and
bound, shared by the solver's z-tests (two-sided stacks, unmatched interiors, rough bases)."""
from __future__ import annotations

import numpy as np

from bsdflab.testing import random_unit_vectors, spherical_directions

# each kind's grazing direction (86-88 deg from the normal), on the light's or the viewer's side
GRAZE = spherical_directions(np.radians([88.0, 86.0, 87.0, 88.0]), [0.5, 1.0, 2.0, 3.0])


def pairs_by_kind(kinds, per_kind: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``per_kind`` random pairs of each (wi, wo) hemisphere kind, ("upper", "lower") and so
    on; the first pair of each kind grazing, the viewer for odd kinds and the light for even."""
    wis, wos = [], []
    for k, (hi, ho) in enumerate(kinds):
        wi = random_unit_vectors(per_kind, seed=seed + 2 * k, hemisphere=hi)
        wo = random_unit_vectors(per_kind, seed=seed + 2 * k + 1, hemisphere=ho)
        if k % 2:  # grazing viewer
            wi[0] = GRAZE[k] * np.array([1.0, 1.0, 1.0 if hi == "upper" else -1.0])
        else:  # grazing light
            wo[0] = GRAZE[k] * np.array([1.0, 1.0, 1.0 if ho == "upper" else -1.0])
        wis.append(wi)
        wos.append(wo)
    return np.concatenate(wis), np.concatenate(wos)


def z_scores(est, ref, ref_err):
    """Per cell, PFMC's distance from the solver beyond the solver's bound in PFMC standard
    errors; and the mean signed z of all cells times sqrt(cells) (a shared bias)."""
    z = (np.abs(est.value - ref) - ref_err) / est.stderr
    signed = (est.value - ref) / np.hypot(est.stderr, ref_err)
    return z, np.mean(signed) * np.sqrt(signed.shape[0])


def assert_solver_matches_pfmc(label, wi, wo, wavelengths, est, ref, ref_err, z_max):
    """The solver z-tests' verdict: every cell's z (``z_scores``) and the shared-bias z
    within ``z_max``; the worst cell named in the failure message."""
    z, mean_z = z_scores(est, ref, ref_err)
    worst = np.unravel_index(np.argmax(z), z.shape)
    print(
        f"{label}: max z {np.max(z):.2f}, sqrt(pairs) mean z {mean_z:.2f}, limit {z_max:.2f}, "
        f"median PFMC rel. error {np.median(est.stderr / ref):.4f}, max solver bound {np.max(ref_err / ref):.1e}"
    )
    assert np.max(z) <= z_max, (
        f"max z {np.max(z):.2f} > {z_max:.2f} at wi {wi[worst[0]]}, wo {wo[worst[0]]}, {wavelengths[worst[1]]} nm: "
        f"PFMC {est.value[worst]:.6g} +- {est.stderr[worst]:.2g}, solver {ref[worst]:.6g}"
    )
    assert abs(mean_z) <= z_max


def hemisphere_integrals(sol, lights, n_mu, n_phi):
    """Integral of eval(wi, light) / |cos theta_light| over wi in the upper and in the lower
    half-space, (lights, 2, C): Gauss-Legendre in the outside cosine, the trapezoid rule in
    azimuth (periodic); every light and half-space in one eval (each call pays a rough top's
    exits set-up: one call of 8 x 3072 pairs costs 7 CPU-s, 8 calls 19)."""
    x, w = np.polynomial.legendre.leggauss(n_mu)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    phi = 2.0 * np.pi * np.arange(n_phi) / n_phi
    t, p = np.meshgrid(np.arccos(mu), phi, indexing="ij")
    up = spherical_directions(t.ravel(), p.ravel())
    half = [up * np.array([1.0, 1.0, h]) for h in (1.0, -1.0)]
    wi = np.concatenate([d for _ in lights for d in half])
    wo = np.concatenate([np.repeat(light, 2 * len(up), axis=0) for light in lights])
    f_cos = sol.eval(wi, wo).reshape(len(lights), 2, len(up), -1) / np.abs(lights[:, :, 2])[:, :, None, None]
    return (2.0 * np.pi / n_phi) * np.sum(np.repeat(w * mu, n_phi)[:, None] * f_cos, axis=2)
