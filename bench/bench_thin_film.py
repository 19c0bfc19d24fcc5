"""Thin-film reflectance: bsdflab (one thread) against tmm and colour on identical inputs.

One evaluation is the unpolarised reflectance of one film for one (wavelength, angle,
thickness) triple. The triples form a grid, which colour's thin_film_tmm takes as an outer
product and bsdflab takes by broadcasting; tmm (pure Python, one triple per call) runs on a
random subset and is scaled per evaluation.

    python3 bench/bench_thin_film.py
"""
import os

os.environ["BSDFLAB_THREADS"] = "1"  # one core for every contender

import time
import warnings

import numpy as np
import tmm
from colour.phenomena import thin_film_tmm

from bsdflab import _core
from bsdflab.optics import film_reflectance

N0, N1, N2 = 1.0, 1.56, 1.83  # air | film | substrate
WAVELENGTHS = np.linspace(380.0, 780.0, 20)
THETAS = np.radians(np.linspace(0.0, 85.0, 20))
THICKNESSES = np.linspace(0.0, 1500.0, 50)
TMM_SAMPLES = 400


def best_times(contenders, repeats=8):
    """Fastest of `repeats` runs of each contender, in seconds. The contenders take turns
    within every round, in a rotating order, so a change in the machine's load or a cache
    left cold by the previous contender hits them all alike."""
    best = {name: np.inf for name in contenders}
    names = list(contenders)
    for round_ in range(repeats):
        for name in names[round_ % len(names):] + names[:round_ % len(names)]:
            start = time.perf_counter()
            contenders[name]()
            best[name] = min(best[name], time.perf_counter() - start)
    return best


def run_bsdflab():
    return film_reflectance((N0, N1, 0.0, N2), WAVELENGTHS[:, None, None], THETAS[None, :, None],
                            thickness_nm=THICKNESSES[None, None, :])


def core_inputs():
    wl, th, d = (a.ravel() for a in np.meshgrid(WAVELENGTHS, THETAS, THICKNESSES, indexing="ij"))
    n = len(wl)
    return (np.full(n, N0, complex), np.full(n, N1, complex), np.full(n, N2, complex), d,
            np.cos(th), wl)


def run_colour():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        R, _ = thin_film_tmm([N0, N1, N2], THICKNESSES, WAVELENGTHS, np.degrees(THETAS))
    return R.mean(axis=-1)  # (W, A, T): unpolarised


def run_tmm(samples):
    return np.array([tmm.unpolarized_RT([N0, N1, N2], [np.inf, THICKNESSES[k], np.inf],
                                        THETAS[j], WAVELENGTHS[i])["R"] for i, j, k in samples])


def main():
    count = WAVELENGTHS.size * THETAS.size * THICKNESSES.size
    rng = np.random.default_rng(0)
    samples = np.stack([rng.integers(0, a.size, TMM_SAMPLES)
                        for a in (WAVELENGTHS, THETAS, THICKNESSES)], axis=1)

    ours, theirs = run_bsdflab(), run_colour()
    reference = run_tmm(samples)
    inputs = core_inputs()

    t = best_times({
        "ours": run_bsdflab,
        "core": lambda: _core.thin_film_reflectance(*inputs),
        "full": lambda: _core.thin_film(*inputs),
        "colour": run_colour,
        "tmm": lambda: run_tmm(samples),
    })
    t_ours, t_core, t_full, t_colour = (t[k] / count for k in ("ours", "core", "full", "colour"))
    t_tmm = t["tmm"] / TMM_SAMPLES

    print(f"thin-film reflectance, {count} (wavelength, angle, thickness) triples, "
          f"bsdflab threads = {_core.worker_count()}")
    print(f"  bsdflab film_reflectance   {t_ours * 1e9:10.1f} ns / evaluation")
    print(f"  bsdflab C++ kernel         {t_core * 1e9:10.1f} ns / evaluation "
          "(_core.thin_film_reflectance, no Python layer)")
    print(f"  bsdflab C++ kernel, all    {t_full * 1e9:10.1f} ns / evaluation "
          "(_core.thin_film: r, t, R, T for s and p)")
    print(f"  colour thin_film_tmm       {t_colour * 1e9:10.1f} ns / evaluation")
    print(f"  tmm unpolarized_RT         {t_tmm * 1e9:10.1f} ns / evaluation "
          f"({TMM_SAMPLES} samples)")
    print(f"  speed-up vs tmm:    {t_tmm / t_ours:9.0f}x   (target >= 1000x)")
    print(f"  speed-up vs colour: {t_colour / t_ours:9.1f}x   (target >= 10x)")
    i, j, k = samples.T
    print(f"  max |R_bsdflab - R_colour| = {np.max(np.abs(ours - theirs)):.2e} over {count}")
    print(f"  max |R_bsdflab - R_tmm|    = {np.max(np.abs(ours[i, j, k] - reference)):.2e} "
          f"over {TMM_SAMPLES}")


if __name__ == "__main__":
    main()
