"""Deliberately broken models, injected into registered checks with Check.with_model: a
`bsdflab validate --plugin` file (checks() returns the checks to add). Each must turn its
rows red and the exit status non-zero: the proof that the report has power."""
from __future__ import annotations

import importlib.util

import numpy as np

import bsdflab
from bsdflab.bsdfs.base import BSDFSample


class ScaledBSDF:
    """A BSDF whose eval and sample weights are `factor` times the real ones (pdf unchanged):
    e.g. a Diffuse 3 % too bright. It claims (to_dict) to be the real model."""

    def __init__(self, inner, factor):
        self.inner, self.factor = inner, factor

    def eval(self, wi, wo, wavelengths=None, lobes=bsdflab.Lobe.ALL, thickness_nm=None):
        return self.factor * self.inner.eval(wi, wo, wavelengths=wavelengths, lobes=lobes, thickness_nm=thickness_nm)

    def pdf(self, wi, wo, lobes=bsdflab.Lobe.ALL, thickness_nm=None, wavelengths=None):
        return self.inner.pdf(wi, wo, lobes=lobes, thickness_nm=thickness_nm, wavelengths=wavelengths)

    def sample(self, wi, u1=None, u2=None, *, seed=0, wavelengths=None, lobes=bsdflab.Lobe.ALL, thickness_nm=None):
        s = self.inner.sample(wi, u1, u2, seed=seed, wavelengths=wavelengths, lobes=lobes, thickness_nm=thickness_nm)
        return BSDFSample(s.wo, self.factor * s.weight, s.pdf, s.lobe, s.eta)

    @property
    def lobes(self):
        return self.inner.lobes

    def to_dict(self):
        return self.inner.to_dict()

    def __repr__(self):
        return f"{self.inner!r} x {self.factor}"


class SkewedSampler(ScaledBSDF):
    """Samples with cos(theta) raised to 0.9 (a skewed density) while pdf() still claims the
    original one; weights stay eval / pdf at the returned direction."""

    def __init__(self, inner):
        super().__init__(inner, 1.0)

    def sample(self, wi, u1=None, u2=None, *, seed=0, wavelengths=None, lobes=bsdflab.Lobe.ALL, thickness_nm=None):
        s = self.inner.sample(wi, u1, u2, seed=seed, wavelengths=wavelengths, lobes=lobes, thickness_nm=thickness_nm)
        wo = np.array(s.wo, dtype=float)
        z = np.sign(wo[:, 2]) * np.abs(wo[:, 2]) ** 0.9
        r = np.sqrt(np.maximum(1 - z * z, 0.0)) / np.maximum(np.hypot(wo[:, 0], wo[:, 1]), 1e-300)
        wo = np.stack([wo[:, 0] * r, wo[:, 1] * r, z], axis=1)
        w = np.asarray(wi, float).reshape(-1, 3)
        value = self.inner.eval(w, wo, wavelengths=wavelengths, lobes=lobes)
        pdf = self.inner.pdf(w, wo, lobes=lobes)
        weight = np.where(pdf[:, None] > 0, value / np.where(pdf > 0, pdf, 1.0)[:, None], 0.0)
        return BSDFSample(wo, weight, pdf, s.lobe, s.eta)


def double_counted_film(n0, n1, n2, d_nm, wavelength_nm, theta):
    """The double-phase film formula of Padrón-Griffe et al. 2023's code (an extra pi on top of
    the signed amplitudes)."""
    from bsdflab.reference.approximations import double_phase_reflectance

    return double_phase_reflectance(n0, n1, n2, d_nm, wavelength_nm, np.cos(theta))


def checks():
    from bsdflab.validation import REGISTRY, load_checks

    load_checks()
    bright = "Diffuse 3 % high (broken on purpose)"
    out = [
        REGISTRY["basic/furnace/diffuse-white"].with_model(
            lambda: ScaledBSDF(bsdflab.Diffuse(1.0), 1.03), "basic/furnace/diffuse-white [broken: 3% high]", bright),
        REGISTRY["basic/chi2/diffuse"].with_model(
            lambda: SkewedSampler(bsdflab.Diffuse(0.5)), "basic/chi2/diffuse [broken: skewed sampler]",
            "Diffuse(0.5) sampling cos^0.9 (broken on purpose)"),
        REGISTRY["films/tmm/single-film"].with_model(
            lambda: double_counted_film, "films/tmm/single-film [broken: double-counted phase]",
            "the double-counted phase (broken on purpose)"),
    ]
    if importlib.util.find_spec("mitsuba") is None:
        return out
    return out + [REGISTRY["basic/mitsuba/diffuse-grey"].with_model(
        lambda: ScaledBSDF(bsdflab.Diffuse(0.5), 1.03), "basic/mitsuba/diffuse-grey [broken: 3% high]", bright)]
