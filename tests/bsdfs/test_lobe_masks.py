"""Lobe masks, for every registered BSDF class x every one of the 64 lobe masks: a mask
restricts a call to part of the BSDF, and nothing outside it may leak through.

For each model, incident direction and mask M:

1. ``sample(wi, lobes=M)`` returns only lobes in M that the model has (a failed sample:
   lobe 0 and weight 0);
2. ``eval(wi, wo, lobes=M)`` and ``pdf(wi, wo, lobes=M)`` are 0 (exactly) for random wo on
   a side where M holds none of the model's non-delta lobes;
3. a sampled non-delta direction's reported pdf is ``pdf(wi, wo, lobes=M)``;
4. mask bits the model lacks change nothing: the samples of M equal (bit for bit, same
   seed) those of M & model.lobes;
5. mass: the mean sample weight under M equals the masked eval integral plus the delta
   lobes of M. Reference: the integral of ``eval(lobes=M)`` over uniform directions (an
   estimator independent of the sampler) plus, per delta lobe in M, the mass that lobe
   carries in an independent unmasked sample. z-tests at family-wise significance
   ALPHA = 0.01, Sidak-corrected over every (model, direction, distinct effective mask);
   an effective mask with no lobe needs exactly zero mass.

Version 4 leaked: RoughDielectric sampled with a mask holding no glossy lobe (NONE,
DIFFUSE, DELTA_REFLECTION, ...) returned a glossy transmission (weight ~0.4) and pdf 2.83
(issue 21, defect 1); Layered.eval/pdf answered DIFFUSE masks though it has no diffuse
lobe, and TabulatedBSDF.pdf ignored its mask.
"""
from __future__ import annotations

import functools

import numpy as np
import pytest

import bsdflab as bl
from bsdflab import Lobe
from bsdflab.bsdfs.base import TYPES
from bsdflab.tables import TableBSDF, TableGrid, tabulate
from bsdflab.testing import random_unit_vectors, sidak_z_limit
from support.directions import directions_at

ALPHA = 0.01
WL = [450.0, 550.0, 650.0]
MASKS = list(range(64))  # every combination of the six lobe bits
N_SAMPLE = 20_000        # per (model, direction, effective mask); half for layered models
N_SHAPE = 2_000          # per mask for the structural checks 1-4
DELTA_BITS = (Lobe.DELTA_REFLECTION, Lobe.DELTA_TRANSMISSION)
FILM = [{"material": 2.0, "thickness_nm": 300.0}]


def _layered_rough_over_diffuse():
    return bl.Layered([bl.RoughDielectric(0.3, 1.5)], [bl.Slab(0.5, sigma_a=0.2)],
                      bl.Diffuse(0.6), samples=4, seed=3)


def _layered_smooth_transmissive():
    return bl.Layered([bl.Dielectric(1.5)], [bl.Slab(1.0, sigma_a=0.1, sigma_s=0.5)],
                      bl.RoughDielectric(0.3, 1.0, 1.5), samples=4, seed=4)


def _layered_clear_smooth():
    # a clear slab between smooth boundaries: delta lobes of the stack, and a rough-base
    # reflection path
    return bl.Layered([bl.Dielectric(1.5)], [bl.Slab(1.0)], bl.Dielectric(1.0, 1.5),
                      samples=4, seed=5)


@functools.cache
def _table():
    model = bl.Layered([bl.RoughDielectric(0.3, 1.5)], [bl.Slab(0.5, sigma_s=1.0)],
                       bl.RoughDielectric(0.4, 1.2, 1.5), samples=4, seed=6)
    return TableBSDF(tabulate(model, TableGrid(3, 4, 3), rel_error=0.2, wavelengths=WL,
                              min_samples=64, max_samples=256, progress=False))


# (name, factory, incident cosines; negative = from below; -0.3 is beyond the critical
# angle of the macro-surface: total internal reflection for most microfacets)
MODELS = [
    ("diffuse", lambda: bl.Diffuse(0.7), (0.6,)),
    ("conductor", lambda: bl.Conductor(material="Au"), (0.6,)),
    ("dielectric", lambda: bl.Dielectric(1.5, 1.0), (0.6, -0.5)),
    ("dielectric_film", lambda: bl.Dielectric(1.5, 1.0, film=FILM), (0.6, -0.5)),
    ("roughconductor", lambda: bl.RoughConductor(0.3, material="Cu"), (0.6,)),
    ("roughconductor_ms", lambda: bl.RoughConductor(0.3, material="Ag", multiscatter=True), (0.6,)),
    ("roughdielectric", lambda: bl.RoughDielectric(0.3, 1.5), (0.6, -0.5, -0.3)),
    ("roughdielectric_ms", lambda: bl.RoughDielectric(0.3, 1.5, multiscatter=True), (0.6,)),
    ("roughdielectric_film", lambda: bl.RoughDielectric(0.3, 1.5, film=FILM), (0.6, -0.5)),
    ("layered_rough", _layered_rough_over_diffuse, (0.6,)),
    ("layered_smooth_transmissive", _layered_smooth_transmissive, (0.6, -0.5)),
    ("layered_clear_smooth", _layered_clear_smooth, (0.6,)),
    ("table", _table, (0.6,)),
]
CASES = [(name, make, c) for name, make, cosines in MODELS for c in cosines]


def _effective_masks(lobes: int) -> list[int]:
    return sorted({m & lobes for m in MASKS})


# Every (model, direction, effective mask) is one z-test of the mass family.
FAMILY = 0
_MODEL_LOBES = {}


def _model(name: str, make):
    m = _MODEL_LOBES.get(name)
    if m is None:
        m = _MODEL_LOBES[name] = make()
    return m


def _family_size() -> int:
    return sum(len(_effective_masks(int(_model(n, mk).lobes))) for n, mk, _ in CASES)


# File-backed readers: every mask is tested on files in tests/measured/test_measured_review.py.
TESTED_ELSEWHERE = {"measured", "merl"}


def product_types() -> set[str]:
    """Every registered product BSDF type (comparison models of bsdflab.reference excluded)."""
    return {n for n in TYPES.names() if not TYPES.get(n).__module__.startswith("bsdflab.reference")}


def test_00_every_registered_class_is_covered():
    covered = {type(_model(n, mk)).type_name for n, mk, _ in CASES}
    expected = product_types() - TESTED_ELSEWHERE
    assert covered == expected, expected ^ covered


def _sample(model, wi, n, mask, seed):
    return model.sample(np.tile(wi, (n, 1)), seed=seed, wavelengths=WL, lobes=mask)


@pytest.mark.parametrize("name, make, cos_theta", CASES)
def test_01_structure_under_every_mask(name, make, cos_theta):
    model = _model(name, make)
    lobes = int(model.lobes)
    wi = directions_at(cos_theta)
    wo = random_unit_vectors(N_SHAPE, seed=11)
    side_nondelta = np.where(wo[:, 2] * wi[2] > 0, int(Lobe.REFLECTION & ~Lobe.DELTA),
                             int(Lobe.TRANSMISSION & ~Lobe.DELTA))
    wi_rows = np.tile(wi, (N_SHAPE, 1))
    reference = {}
    for mask in MASKS:
        s = _sample(model, wi, N_SHAPE, mask, seed=12)
        lobe = s.lobe.astype(int)
        bad = (lobe != 0) & ((lobe & ~(mask & lobes)) != 0)
        assert not bad.any(), (f"{name}: mask {Lobe(mask)!r} sampled lobe(s) "
                               f"{sorted({Lobe(int(x)) for x in lobe[bad]}, key=int)}")
        assert np.all(s.weight[lobe == 0] == 0), f"{name}: failed samples carry weight"
        # 3: the density reported with a non-delta sample is pdf() under the same mask
        nd = (lobe != 0) & ((lobe & int(Lobe.DELTA)) == 0)
        if nd.any():
            p = model.pdf(wi_rows[nd], s.wo[nd], lobes=mask, wavelengths=WL)
            assert np.allclose(p, s.pdf[nd], rtol=1e-9, atol=0), f"{name}: mask {Lobe(mask)!r}"
        # 4: bits outside the model's lobes change nothing
        eff = mask & lobes
        if eff in reference:
            r = reference[eff]
            assert np.array_equal(s.lobe, r.lobe) and np.array_equal(s.weight, r.weight), \
                f"{name}: mask {Lobe(mask)!r} differs from {Lobe(eff)!r}"
        else:
            reference[eff] = s
        # 2: eval and pdf vanish where the mask holds none of the model's lobes of wo's side
        off = (side_nondelta & mask & lobes) == 0
        if off.any():
            e = model.eval(wi_rows[off], wo[off], wavelengths=WL, lobes=mask)
            p = model.pdf(wi_rows[off], wo[off], lobes=mask, wavelengths=WL)
            assert np.all(e == 0), f"{name}: eval leaks under mask {Lobe(mask)!r}"
            assert np.all(p == 0), f"{name}: pdf leaks under mask {Lobe(mask)!r}: {p.max():.3g}"


@pytest.mark.parametrize("name, make, cos_theta", CASES)
def test_02_masked_mass_equals_masked_eval_integral(name, make, cos_theta):
    model = _model(name, make)
    lobes = int(model.lobes)
    wi = directions_at(cos_theta)
    limit = sidak_z_limit(ALPHA, _family_size())
    layered = isinstance(model, (bl.Layered, TableBSDF))  # stochastic or costly eval
    # independent references: the unmasked sample's per-lobe delta mass, and eval's
    # integral over uniform directions
    n = N_SAMPLE // 2 if layered else N_SAMPLE
    full = _sample(model, wi, n, int(Lobe.ALL), seed=21)
    n_uniform = 4_000 if layered else 200_000
    wo = random_unit_vectors(n_uniform, seed=22)
    wi_rows = np.tile(wi, (n_uniform, 1))
    for mask in _effective_masks(lobes):
        s = _sample(model, wi, n, mask, seed=23)
        mass = s.weight.mean(axis=0)
        mass_err = s.weight.std(axis=0, ddof=1) / np.sqrt(n)
        values = 4 * np.pi * model.eval(wi_rows, wo, wavelengths=WL, lobes=mask & ~int(Lobe.DELTA))
        ref = values.mean(axis=0)
        ref_var = values.var(axis=0, ddof=1) / n_uniform
        for d in DELTA_BITS:
            if mask & d:
                x = np.where((full.lobe == d)[:, None], full.weight, 0.0)
                ref = ref + x.mean(axis=0)
                ref_var = ref_var + x.var(axis=0, ddof=1) / n
        if mask == 0:
            assert np.all(s.weight == 0) and np.all(s.lobe == 0), f"{name}: mask NONE samples"
            continue
        err = np.sqrt(mass_err ** 2 + ref_var)
        exact = err == 0  # no noise on either side (e.g. total internal reflection): equal
        assert np.allclose(mass[exact], ref[exact], rtol=1e-12, atol=0), \
            f"{name}: mask {Lobe(mask)!r}: {mass} vs {ref}"
        z = np.where(exact, 0.0, (mass - ref) / np.where(exact, 1.0, err))
        assert np.max(np.abs(z)) < limit, \
            f"{name}, cos {cos_theta}, mask {Lobe(mask)!r}: mass {mass} vs {ref} (z {z})"
