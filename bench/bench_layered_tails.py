"""Heavy tails of the layered PFMC walk: how the per-walk contributions are distributed.

The single-strategy path classes (A alone through delta exit-side boundaries, B alone
after a delta reflection, rough interior crossings) are unbiased but can be heavy-tailed:
a few walks carry much of the estimate, and a standard error from a few thousand walks
then understates the spread. Per configuration and direction pair this draws W walks one
at a time (samples=1, seeds 0..W-1: independent walks) and prints
  * max/mean: the largest walk contribution over the mean,
  * top share: the share of the sum carried by the largest 0.1 % of walks,
  * excess kurtosis of the contributions (0 for a normal; the standard error of a mean of
    n walks is itself uncertain by about sqrt((kurtosis + 2) / (4 n)) relative),
  * n for 1 %: walks for a 1 % relative standard error, and the relative uncertainty of
    that standard error at n (from the kurtosis).
Run: python bench/bench_layered_tails.py [--walks 20000]
"""
from __future__ import annotations

import argparse

import numpy as np

import bsdflab as bl
from bsdflab.testing import spherical_directions

WL = np.array([550.0])


def configurations():
    glass = bl.RoughDielectric(0.3, 1.5)
    return {
        "snake (xenopeltis), 550 nm": bl.presets.xenopeltis(),
        "rough top | smooth 1.5/1.3 interior | Au base (A through delta)": bl.Layered(
            [glass, bl.Dielectric(1.3, 1.5)], [bl.Slab(0.5, sigma_s=0.5), bl.Slab(0.5, sigma_a=0.2)],
            bl.RoughConductor(0.2, material="Au", ext_ior=1.3)),
        "rough top | alpha 0.03 interior (rough crossing)": bl.Layered(
            [glass, bl.RoughDielectric(0.03, 1.3, 1.5)], [bl.Slab(0.5, sigma_s=0.5), bl.Slab(0.5)],
            bl.Diffuse(0.6)),
        "rough top | near-matched smooth base 1.5/1.52 (B after delta reflection)": bl.Layered(
            [glass], [bl.Slab(0.5, sigma_a=0.1)], bl.Dielectric(1.52, 1.5)),
        "smooth top | scattering slab | diffuse (plastic)": bl.Layered(
            [bl.Dielectric(1.5)], [bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0)], bl.Diffuse(0.6)),
    }


def walk_values(model, wi, wo, walks: int) -> np.ndarray:
    # the walks alone (the top's exact reflection, a constant, left out)
    core = model._core(WL).scattered_part()
    a, b = wi[None, :], wo[None, :]
    return np.array([core.estimate(a, b, int(bl.Lobe.ALL), None, 1, s)[0][0, 0] for s in range(walks)])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--walks", type=int, default=20_000)
    args = ap.parse_args()
    pairs = [(spherical_directions(np.radians(ti), 0.0), spherical_directions(np.radians(to), np.pi * po))
             for ti, to, po in ((10, 20, 1.0), (60, 70, 0.5), (80, 80, 1.0))]
    print(f"{args.walks} walks per pair, 550 nm; (theta_i, theta_o, phi_o) = (10,20,180), (60,70,90), (80,80,180)")
    for name, model in configurations().items():
        print(name)
        for wi, wo in pairs:
            x = walk_values(model, wi, wo, args.walks)
            top = np.sort(x)[::-1][: max(1, args.walks // 1000)]
            mean, sd = x.mean(), x.std(ddof=1)
            kurt = float(np.mean((x - mean) ** 4) / sd ** 4 - 3) if sd > 0 else 0.0
            n1 = (sd / (0.01 * mean)) ** 2 if mean > 0 else np.inf
            se_unc = np.sqrt((kurt + 2) / (4 * max(n1, 1)))
            print(f"  max/mean {x.max() / mean:8.1f}  top 0.1 % share {top.sum() / x.sum():6.3f}  "
                  f"excess kurtosis {kurt:9.1f}  n for 1 % {n1:9.0f}  stderr uncertainty there {se_unc:.3f}")


if __name__ == "__main__":
    main()
