"""The comparison BSDF ``cycles_thin_film_comparison`` and the core's ``TabulatedTerm`` under it.

Sampling the smooth, opaque surface returns the mirror direction with weight R(cos theta):
it must equal the model's reflectance (linear interpolation of a 1025-row table of a
smooth function: within 2e-5 of the model at arbitrary angles), for both models, and the
core must refuse a malformed table with a ValueError.
"""
from __future__ import annotations

import numpy as np
import pytest

from bsdflab import _core
from bsdflab.bsdfs.base import from_dict
from bsdflab.lobes import Lobe
from bsdflab.reference.approximations.cycles_bsdf import CyclesThinFilmComparison


@pytest.mark.parametrize("model", ["cycles", "exact"])
def test_sampled_weight_is_the_models_reflectance(model):
    b = from_dict({"type": "cycles_thin_film_comparison", "film_ior": 1.83, "base_ior": 1.5515,
                   "film_thickness_nm": 400.0, "model": model})
    cos = np.array([0.999, 0.9, 0.71, 0.5, 0.33, 0.2])
    wi = np.stack([np.sqrt(1 - cos**2), np.zeros_like(cos), cos], axis=-1)
    s = b.sample(wi)
    assert np.all(s.lobe == int(Lobe.DELTA_REFLECTION))
    np.testing.assert_allclose(s.wo, wi * [-1, -1, 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(s.weight, b.reflectance(cos), rtol=0, atol=2e-5)
    assert b.to_dict()["model"] == model and isinstance(b, CyclesThinFilmComparison)


def test_bad_tables_and_parameters_are_refused():
    with pytest.raises(ValueError):
        _core.TabulatedTerm([[0.5, 0.5, 0.5]])              # one row
    with pytest.raises(ValueError):
        _core.TabulatedTerm([[0.5, 0.5], [0.5, 1.5]])        # above 1
    with pytest.raises(ValueError):
        _core.TabulatedTerm([[0.5, 0.5], [0.5]])             # ragged
    with pytest.raises(ValueError, match="film_ior"):
        CyclesThinFilmComparison(5.0, 1.5, 400.0)
    with pytest.raises(ValueError, match="model"):
        CyclesThinFilmComparison(1.8, 1.5, 400.0, model="mitsuba")
