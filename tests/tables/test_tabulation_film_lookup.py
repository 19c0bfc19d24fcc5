"""The tabulator's film lookup (core/include/bsdflab/film_lookup.h, estimator version 4).

1. The lookup against the exact FilmTerm (Airy sums, 81 wavelengths) at random off-grid
   cosines from both sides and densely around the critical angle of total internal
   reflection: a deterministic interpolation error, bounded by the stated
   FilmLookupTerm bound MAX_ERROR (1e-7 absolute on R and T), not a statistical tolerance.
2. Tables built with the lookup against tables built with the exact film (film_lookup=False):
   a) the same seed (common random numbers: the walks differ only where R, T differ by
      <= 1e-7, so the paired difference measures the lookup's bias with almost no noise):
      below 1e-6 relative table-wide and 1e-5 per cell, far below the 2 % noise;
   b) independent seeds: per cell, z = (a - b) / hypot(se_a, se_b) of the luminance, all
      cells within the Sidak limit at ALPHA = 0.01 over the cells, and the table-wide mean
      of the luminance by a two-sided z-test at ALPHA.
"""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl
from bsdflab import _core
from bsdflab.bsdfs.interface_term import make_term
from bsdflab.presets import FILM_THICKNESS_NM, iridophore_stack, preset
from bsdflab.spectra import DEFAULT_WAVELENGTHS
from bsdflab.tables import TableGrid, tabulate
from bsdflab.tables.stages import _tabulator, cell_count, finish_cells, floor_scale, pilot_cells
from bsdflab.testing import sidak_z_limit

MAX_ERROR = 1e-7
ALPHA = 0.01
NODES = (0.85 * FILM_THICKNESS_NM, 1.15 * FILM_THICKNESS_NM)  # two of the snake's nodes


def exact_term(top, wl=DEFAULT_WAVELENGTHS):
    return make_term(np.asarray(wl), top.ext_ior, top.film, int_ior=top.int_ior)


def max_error(lookup, exact, cosines, thickness):
    worst = 0.0
    for c in cosines:
        a, b = np.array(lookup.eval(c, thickness)), np.array(exact.eval(c, thickness))
        worst = max(worst, float(np.abs(a - b).max()))
    return worst


def probe_cosines(kink, n=600, seed=0):
    """Random cosines over both sides plus a dense run around +-kink (TIR from below)."""
    rng = np.random.default_rng(seed)
    # Not cos = k itself: there the exact term is off by up to ~1e-7 from its own limit
    # (T ~ sqrt of a difference cancelled to rounding), which the lookup returns.
    near = kink + np.concatenate([rng.uniform(-2e-3, 2e-3, 100), [1e-12, -1e-12, 1e-9, -1e-9]])
    return np.concatenate([rng.uniform(-1, 1, n), -near, near, [0.0, 1.0, -1.0, -1e-9, 1e-9]])


@pytest.mark.parametrize("thickness", [NODES[0], FILM_THICKNESS_NM, NODES[1], -1.0])
def test_01_snake_film_lookup_within_bound(thickness):
    top = preset("xenopeltis").interfaces[0]
    exact = exact_term(top)
    lookup = _core.FilmLookupTerm.build(exact, thickness)
    assert lookup is not None and lookup.measured_error <= MAX_ERROR
    k = lookup.kink(1)
    # Keratin (1.5515) below air: total internal reflection from below at cos 0.7644.
    assert k == pytest.approx(np.sqrt(1 - (bl.presets.AIR_IOR / bl.presets.KERATIN_IOR_550) ** 2), rel=1e-12)
    assert lookup.kink(0) == 0.0
    assert max_error(lookup, exact, probe_cosines(k), thickness) <= MAX_ERROR


def film_term(ext_ior, layers, substrate, transmits=True, wl=DEFAULT_WAVELENGTHS):
    """A FilmTerm from (index, thickness nm) layers over a per-wavelength substrate index."""
    wl = np.asarray(wl, dtype=float)
    return _core.FilmTerm(list(wl), ext_ior, [[complex(n)] * len(wl) for n, _ in layers],
                          [d for _, d in layers], list(np.broadcast_to(substrate, wl.shape).astype(complex)),
                          transmits)


def test_02_other_films_within_bound_or_refused():
    """A 9-layer iridophore stack; a film on a conductor (opaque: nothing from below); a
    denser exterior, so that TIR happens from ABOVE (the kink moves to side 0), with a film
    less dense than the exterior (no kink: a layer's response depends on q^2 only): all
    looked up within the bound. A dispersive substrate has a critical angle per channel,
    which the one split cannot place: build() refuses (None) instead of answering worse."""
    stack = [(layer["material"], layer["thickness_nm"]) for layer in iridophore_stack()]
    cases = [film_term(1.0, stack, 1.55), film_term(1.0, [(1.4, 300.0)], 0.2 + 3.0j, transmits=False),
             film_term(1.6, [(1.3, 200.0)], 1.33)]
    for term in cases:
        lookup = _core.FilmLookupTerm.build(term, -1.0)
        assert lookup is not None
        kink = max(lookup.kink(0), lookup.kink(1))
        assert max_error(lookup, term, probe_cosines(kink, n=300), -1.0) <= MAX_ERROR
    assert cases[2].eta < 1 and cases[2].transmissive and 0 < _core.FilmLookupTerm.build(cases[2], -1.0).kink(0)
    dispersive = film_term(1.0, [(1.8, 400.0)], np.linspace(1.60, 1.50, len(DEFAULT_WAVELENGTHS)))
    assert _core.FilmLookupTerm.build(dispersive, -1.0) is None


def test_03_other_thickness_is_exact():
    """A query at a thickness other than the lookup's is answered by the exact term."""
    top = preset("xenopeltis").interfaces[0]
    exact = exact_term(top)
    lookup = _core.FilmLookupTerm.build(exact, 400.0)
    for c in (0.3, -0.9):
        assert lookup.eval(c, 410.0) == exact.eval(c, 410.0)


def snake_model():
    return bl.presets.xenopeltis()


GRID = TableGrid(3, 4, 3, NODES)  # 72 cells, reflection only


def test_04_paired_tables_measure_the_lookup_bias():
    """Same seed, lookup vs exact film: the common random numbers cancel the walk noise, so
    the difference is the lookup's effect: below 1e-6 relative table-wide and 1e-5 per
    cell above 1 % of the maximum, against the 5 % target noise. The table's meta records
    the lookup's measured error."""
    kw = dict(grid=GRID, rel_error=0.05, min_samples=128, seed=3, progress=False)
    new = tabulate(snake_model(), film_lookup=True, **kw)
    old = tabulate(snake_model(), film_lookup=False, **kw)
    assert 0 < new.meta["film_lookup_error"] <= MAX_ERROR and old.meta["film_lookup_error"] is None
    a, b = new.values.astype(float), old.values.astype(float)
    # Measured: -1.4e-9 table-wide, 8.5e-8 at most per cell (most cells bit-equal in float32).
    assert abs(a.sum() / b.sum() - 1) < 1e-6
    big = b > 0.01 * b.max()
    assert np.abs(a[big] / b[big] - 1).max() < 1e-5
    assert np.array_equal(new.samples, old.samples)
    assert not np.array_equal(new.values, old.values)  # the walks did read the lookup


def luminance(film_lookup, seed, model=None, grid=GRID, wavelengths=None, rel_error=0.03, min_samples=128):
    """(luminance, its standard error) per cell from the stage functions (which report
    the luminance's own error: the channels share walks)."""
    model = model or snake_model()
    n = cell_count(model, grid)
    kw = dict(min_samples=min_samples, seed=seed, wavelengths=wavelengths)
    pilot = pilot_cells(model, grid, range(n), film_lookup=film_lookup, **kw)
    part = finish_cells(model, grid, range(n), pilot, floor_scale(model, grid, pilot, **kw),
                        rel_error=rel_error, film_lookup=film_lookup, **kw)
    return part.lum, part.lum_error


def test_05_lookup_table_agrees_with_exact_table_independent_seeds():
    """Independent seeds: per-cell and table-wide z-tests of the luminance (module doc)."""
    (la, ea), (lb, eb) = luminance(True, 11), luminance(False, 12)
    z = (la - lb) / np.hypot(ea, eb)
    assert np.abs(z).max() < sidak_z_limit(ALPHA, z.size), z
    m_z = (la.mean() - lb.mean()) / (np.sqrt((ea ** 2).sum() + (eb ** 2).sum()) / la.size)
    assert abs(m_z) < sidak_z_limit(ALPHA, 1), m_z


def test_06_every_film_boundary_is_looked_up_and_agrees():
    """The copy reaches every boundary kind: a smooth film top (delta region solve), a
    rough film on an interior boundary, a film-coated rough conductor base. Here the paired
    comparison of test 04 does not apply: a TIR reflection's R = 1 becomes 1 - 1 ulp, so a
    walk whose throughput sat exactly at its entry value now draws a roulette number and the
    cell's later walks shift streams (no bias: every walk stays an unbiased sample). So:
    independent seeds, per-cell and table-wide z-tests (module doc), with each cell's two
    channels' mean as its luminance."""
    film = [{"material": 1.8, "thickness_nm": 320.0}]
    model = bl.Layered([bl.Dielectric(1.5, 1.0, film=film), bl.RoughDielectric(0.2, 1.4, 1.5, film=film)],
                       [bl.Slab(0.5, sigma_a=0.3, sigma_s=0.5), bl.Slab(0.5, sigma_s=0.3)],
                       bl.RoughConductor(0.3, eta=0.2, k=3.0, ext_ior=1.4, film=film))
    grid = TableGrid(2, 3, 3, (300.0, 340.0))
    kw = dict(wavelengths=[450.0, 600.0], rel_error=0.05, min_samples=64)
    (la, ea), (lb, eb) = luminance(True, 21, model, grid, **kw), luminance(False, 22, model, grid, **kw)
    z = (la - lb) / np.hypot(ea, eb)
    assert np.abs(z).max() < sidak_z_limit(ALPHA, z.size), z
    m_z = (la.mean() - lb.mean()) / (np.sqrt((ea ** 2).sum() + (eb ** 2).sum()) / la.size)
    assert abs(m_z) < sidak_z_limit(ALPHA, 1), m_z
    tab = _tabulator(model, grid, kw["wavelengths"], min_samples=1, max_samples=1, seed=0, rel_error=0.01)
    assert 0 < tab.film_lookup_error <= MAX_ERROR


def test_07_film_lookup_flag_is_validated():
    with pytest.raises(ValueError, match="film_lookup"):
        tabulate(snake_model(), GRID, film_lookup="yes", progress=False)
    with pytest.raises(ValueError, match="film_lookup"):
        pilot_cells(snake_model(), GRID, range(3), film_lookup=1)


def dense_probe(lookup, per_interval=16):
    """Cosines at `per_interval` points of every interval of every segment (in the lookup's
    variable v, cos = k + (end - k) v^2), plus s = (3 - sqrt 5) / 2 from each segment end,
    where the one-sided cubic stencil's error factor |s (s-1) (s-2) (s-3)| peaks (1.0; the
    midpoint gives 0.94): the build's check points do not sit there."""
    n = lookup.intervals
    s_peak = (3 - np.sqrt(5)) / 2
    v = np.concatenate([(np.arange(n)[:, None] + (np.arange(per_interval) + 0.5) / per_interval).ravel() / n,
                        [s_peak / n, 1 - s_peak / n]])
    out = []
    for side, sign in ((0, 1.0), (1, -1.0)):
        k = lookup.kink(side)
        for lo, hi in ((k, 1.0), (0.0, k)) if k > 0 else ((0.0, 1.0),):
            cos = lo + (hi - lo) * v ** 2 if lo == k else hi - (hi - lo) * v ** 2
            out.append(sign * cos[(cos > 0) & (cos < 1)])
    return np.concatenate(out)


@pytest.mark.parametrize("thickness", [FILM_THICKNESS_NM, 2540.0])
def test_08_bound_holds_between_the_build_check_points(thickness):
    """The stated bound is an upper bound, not the build's check-point maximum: the
    independent review found the check points ~7 % below the true maximum (a 2540 nm film
    was accepted at 9.4e-8 checked with 1.01e-7 true when the build accepted at the bound
    itself); the build now accepts at half the bound, and the dense probe confirms it."""
    top = preset("xenopeltis").interfaces[0]
    exact = exact_term(top)
    lookup = _core.FilmLookupTerm.build(exact, thickness)
    assert lookup is not None
    worst = max_error(lookup, exact, dense_probe(lookup), thickness)
    assert worst <= MAX_ERROR, worst
    assert worst <= 1.1 * lookup.measured_error, (worst, lookup.measured_error)
