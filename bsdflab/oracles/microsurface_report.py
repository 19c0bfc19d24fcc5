"""The energy of bsdflab's rough interfaces against the microsurface random walk: the
numbers quoted in docs/rough_interfaces.md.

    python -m bsdflab.oracles.microsurface_report [--walks 100000]

For each configuration and incident angle: the energy scattered (R + T, transmission in
flux units) and the reflected part R by bsdflab's single-scattering model, by its
Kulla-Conty compensated model (multiscatter=True), and by the random walk of Heitz et al.
2016 (all scattering orders), each +- one standard error. Lossless configurations must
read R + T = 1 for the walk and the compensated model.
"""
from __future__ import annotations

import argparse

import numpy as np

from bsdflab.bsdfs import RoughConductor, RoughDielectric
from bsdflab.lobes import Lobe
from bsdflab.oracles.microsurface import random_walk


def _model_energy(bsdf, wi: np.ndarray, n: int, wavelength: float, seed: int):
    s = bsdf.sample(np.tile(wi, (n, 1)), seed=seed, wavelengths=[wavelength])
    w = s.weight[:, 0]
    t = s.lobe == int(Lobe.GLOSSY_TRANSMISSION)
    total = np.where(t, w * s.eta**2, w)
    refl = np.where(s.lobe == int(Lobe.GLOSSY_REFLECTION), w, 0.0)
    se = lambda x: x.std() / np.sqrt(n)
    return total.mean(), se(total), refl.mean(), se(refl)


def rows(walks: int = 100_000, seed: int = 0):
    """(label, angle in deg, side, [(model name, E, sE, R, sR)]) of the standard report."""
    configs = []
    for dist in ("ggx", "beckmann"):
        for alpha in (0.3, 0.8):
            configs.append((f"dielectric eta 1.5 {dist} a{alpha}", dist, alpha, 1.5, None, 550.0,
                            lambda ms, d=dist, a=alpha: RoughDielectric(a, 1.5, 1.0, distribution=d,
                                                                        multiscatter=ms)))
            configs.append((f"white conductor {dist} a{alpha}", dist, alpha, None, None, 550.0,
                            lambda ms, d=dist, a=alpha: RoughConductor(a, distribution=d,
                                                                       multiscatter=ms)))
    for alpha in (0.3, 0.8):
        au = RoughConductor(alpha, material="Au")
        n_rel = (au.eta.at([550.0])[0] + 1j * au.k.at([550.0])[0]) / au.ext_ior
        configs.append((f"Au 550 nm ggx a{alpha}", "ggx", alpha, None, n_rel, 550.0,
                        lambda ms, a=alpha: RoughConductor(a, material="Au", multiscatter=ms)))
    out = []
    for label, dist, alpha, eta, n_rel, wl, make in configs:
        sides = (1, -1) if eta else (1,)
        for side in sides:
            for deg in (0, 30, 60, 80):
                t = np.radians(deg)
                wi = np.array([np.sin(t), 0.0, side * np.cos(t)])
                res = []
                for name, ms_flag in (("single", False), ("compensated", True)):
                    res.append((name, *_model_energy(make(ms_flag), wi, walks, wl, seed)))
                w = random_walk(wi, walks, alpha, dist, eta=eta, conductor_index=n_rel, seed=seed)
                e, se = w.moments(w.side != 0)
                r, sr = w.moments(w.side == side)
                res.append(("walk", e[0], se[0], r[0], sr[0]))
                out.append((label, deg, side, res))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--walks", type=int, default=100_000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    for label, deg, side, res in rows(args.walks, args.seed):
        where = "from outside" if side > 0 else "from inside"
        cells = "  ".join(f"{n}: R+T {e:.4f}+-{se:.4f} R {r:.4f}" for n, e, se, r, _ in res)
        print(f"{label:32s} {deg:3d} deg {where:12s} {cells}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
