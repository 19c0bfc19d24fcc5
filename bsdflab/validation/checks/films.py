"""Thin films: bsdflab's exact Airy / recursive-Airy optics against tmm and colour-science,
and the double-phase formula's counter-example. (The approximations study: approximations.py.)"""
from __future__ import annotations

import warnings

import numpy as np

from bsdflab.validation.checks._common import log_error_histogram
from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import REGISTRY, Outcome, effort

ROUND_OFF = 1e-10
ROUND_OFF_TOLERANCE = ("1e-10 absolute on R and T: both sides are exact closed forms in double "
                       "precision; the Airy recursion's rounding stays below 1e-12 for these stacks, "
                       "so 1e-10 leaves two orders of margin and still fails any physics error")


def bsdflab_film(n0, n1, n2, d_nm, wavelength_nm, theta):
    """The model under test: unpolarised reflectance of one film (bsdflab.optics)."""
    from bsdflab.optics import film_reflectance

    return film_reflectance((n0, n1, float(d_nm), n2), wavelength_nm, theta)


def _random_films(rng, n):
    for _ in range(n):
        n0 = 1.0 if rng.random() < 0.7 else rng.uniform(1.0, 1.8)
        yield (n0, rng.uniform(1.0, 2.6), rng.uniform(1.0, 2.6), rng.uniform(0.0, 1500.0),
               rng.uniform(380.0, 780.0, 4), np.radians(rng.uniform(0.0, 85.0, 4)))


@REGISTRY.check(name="films/tmm/single-film", family="films", title="Single films against tmm",
                model="bsdflab.optics.film_reflectance (exact Airy sum)",
                reference="tmm.unpolarized_RT (S. Byrnes' transfer-matrix package)",
                statistic="max |R - R_tmm| over random films (indices 1-2.6, 0-1500 nm, 0-85 deg)",
                tolerance=ROUND_OFF_TOLERANCE, effort=effort({"films": 60}, {"films": 400}, {"films": 2000}),
                make_model=lambda: bsdflab_film, seed=21, requires=("tmm",))
def _single_film(ctx):
    import tmm

    rng = np.random.default_rng(ctx.seed)
    ours, ref = [], []
    for n0, n1, n2, d, wl, th in _random_films(rng, int(ctx.effort["films"])):
        ours.append(np.broadcast_to(ctx.model(n0, n1, n2, d, wl, th), wl.shape))
        ref.append([tmm.unpolarized_RT([n0, n1, n2], [np.inf, d, np.inf], t, w)["R"] for w, t in zip(wl, th)])
    ours, ref = np.concatenate(ours), np.concatenate(ref)
    err = np.abs(ours - ref)
    fig, (a, b) = new_figure(9.0, 3.2, cols=2)
    a.plot(ref, ours, ".", ms=3)
    a.plot([0, 1], [0, 1], "k--", lw=0.8)
    a.set_xlabel("R (tmm)")
    a.set_ylabel("R (model)")
    log_error_histogram(b, err, ROUND_OFF, "log10 |R - R_tmm|")
    ctx.figure(fig, "reflectance of random single films against tmm")
    worst = float(err.max())
    return Outcome(worst <= ROUND_OFF, worst, ROUND_OFF, "<=", f"max |dR| {worst:.2e} over {len(err)} evaluations")


def _random_stack(rng):
    from bsdflab.optics import Constant, FilmLayer, FilmStack

    layers = [FilmLayer(Constant(rng.uniform(1.0, 3.0), rng.uniform(0.0, 1.5) if rng.random() < 0.3 else 0.0),
                    rng.uniform(0.0, 1000.0)) for _ in range(rng.integers(1, 7))]
    return FilmStack(Constant(rng.uniform(1.0, 2.0)), layers,
                     Constant(rng.uniform(1.0, 3.0), rng.uniform(0.0, 2.0) if rng.random() < 0.5 else 0.0))


@REGISTRY.check(name="films/tmm/stacks", family="films", title="Multilayer stacks (absorbing too) against tmm",
                model="bsdflab.optics film_reflectance / film_transmittance (recursive Airy)",
                reference="tmm.coh_tmm, s and p", statistic="max |dR|, |dT| over random stacks of 1-6 layers",
                tolerance=ROUND_OFF_TOLERANCE, effort=effort({"stacks": 40}, {"stacks": 300}, {"stacks": 1500}),
                seed=22, requires=("tmm",))
def _stacks(ctx):
    import tmm

    from bsdflab.optics import film_reflectance, film_transmittance

    rng = np.random.default_rng(ctx.seed)
    worst = 0.0
    for _ in range(int(ctx.effort["stacks"])):
        stack = _random_stack(rng)
        media = [stack.incident, *(layer.material for layer in stack.layers), stack.substrate]
        n = np.array([complex(m.n, m.k) for m in media])
        d = [np.inf, *(layer.thickness_nm for layer in stack.layers), np.inf]
        wl, th = rng.uniform(380.0, 780.0, 3), np.radians(rng.uniform(0.0, 89.0, 3))
        for pol in "sp":
            R = film_reflectance(stack, wl, th, polarisation=pol)
            T = film_transmittance(stack, wl, th, polarisation=pol)
            for i in range(3):
                ref = tmm.coh_tmm(pol, n, d, th[i], wl[i])
                worst = max(worst, abs(R[i] - ref["R"]), abs(T[i] - ref["T"]))
    return Outcome(worst <= ROUND_OFF, worst, ROUND_OFF, "<=", f"max |dR|, |dT| = {worst:.2e}")


@REGISTRY.check(name="films/colour/thickness-sweep", family="films",
                title="Thickness sweep against colour-science", model="bsdflab.optics.film_reflectance",
                reference="colour.phenomena.thin_film_tmm", statistic="max |dR| over the sweep, s and p",
                tolerance=ROUND_OFF_TOLERANCE, effort=effort({"thicknesses": 61}, {"thicknesses": 301}),
                seed=0)
def _colour_sweep(ctx):
    from colour.phenomena import thin_film_tmm

    from bsdflab.optics import film_reflectance

    n0, n1, n2 = 1.0, 1.83, 1.5515   # the snake's film: guanine on keratin
    d = np.linspace(0.0, 1500.0, int(ctx.effort["thicknesses"]))
    wl = np.array([450.0, 550.0, 650.0])
    theta = np.array([0.0, 30.0, 60.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        R, _ = thin_film_tmm([n0, n1, n2], d, wl, theta)  # (W, A, T, [s, p])
    worst = 0.0
    args = ((n0, n1, 0.0, n2), wl[:, None, None], np.radians(theta)[None, :, None])
    ours = {}
    for i, pol in enumerate("sp"):
        ours[pol] = film_reflectance(*args, polarisation=pol, thickness_nm=d[None, None, :])
        worst = max(worst, float(np.max(np.abs(ours[pol] - R[..., i]))))
    fig, ax = new_figure(8.0, 3.0)
    for w in range(3):
        ax.plot(d, 0.5 * (ours["s"][w, 0] + ours["p"][w, 0]), label=f"bsdflab {wl[w]:g} nm")
        ax.plot(d[::6], R[w, 0, ::6].mean(axis=-1), "k.", ms=3)
    ax.set_xlabel("film thickness (nm), guanine 1.83 on keratin 1.55, normal incidence")
    ax.set_ylabel("R")
    ax.legend(fontsize=7, title="dots: colour-science", title_fontsize=7)
    ctx.figure(fig, "reflectance against thickness: bsdflab (lines) and colour-science (dots)")
    return Outcome(worst <= ROUND_OFF, worst, ROUND_OFF, "<=", f"max |dR| {worst:.2e}")


@REGISTRY.check(name="films/double-phase-counter-example", family="films",
                title="The double-counted reflection phase (Padrón-Griffe et al. 2023's code), "
                      "reproduced and corrected",
                model="bsdflab.optics.film_reflectance and the double-phase formula (reference/approximations)",
                reference="tmm (exact 0.0218; the double-phase formula gives 0.0854)",
                statistic="|R_bsdflab - R_tmm| at n = 1 / 1.56 / 1.83, 400 nm, 475 nm, 0.4 rad",
                tolerance="1e-14 (round-off); the double-phase value must round to 0.0854 and tmm's to 0.0218",
                effort=effort({}, {}), seed=0, requires=("tmm",))
def _double_phase_counter_example(ctx):
    import tmm

    from bsdflab.optics import film_reflectance
    from bsdflab.reference.approximations import double_phase_reflectance

    n0, n1, n2, d, wl, theta = 1.0, 1.56, 1.83, 400.0, 475.0, 0.4
    exact = tmm.unpolarized_RT([n0, n1, n2], [np.inf, d, np.inf], theta, wl)["R"]
    doubled = float(double_phase_reflectance(n0, n1, n2, d, wl, np.cos(theta)))
    ours = float(film_reflectance((n0, n1, d, n2), wl, theta))
    err = abs(ours - exact)
    ok = err < 1e-14 and round(exact, 4) == 0.0218 and round(doubled, 4) == 0.0854
    return Outcome(ok, err, 1e-14, "<", f"tmm {exact:.4f}, double phase {doubled:.4f}, bsdflab {ours:.4f}",
                   {"tmm": exact, "double_phase": doubled, "bsdflab": ours})
