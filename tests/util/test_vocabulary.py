"""Issue 34's one vocabulary: the new names work silently, the old ones still work and say
(FutureWarning) what to write instead (bsdflab/util/deprecation.py)."""

from __future__ import annotations

import warnings

import pytest

from bsdflab import optics
from bsdflab.optics import FilmLayer
from bsdflab.oracles import _ad_operators


def silently(f):
    """f() with every warning an error: the new names must not warn."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return f()


def test_film_layer_is_the_name_and_layer_still_imports():
    silently(lambda: FilmLayer(1.5, 100.0))
    for module in (optics, optics.thin_film):
        with pytest.warns(FutureWarning, match="'FilmLayer'"):
            old = module.Layer
        assert old is FilmLayer
    with pytest.warns(FutureWarning, match="'LayerOperators'"):
        assert _ad_operators.Layer is _ad_operators.LayerOperators
    with pytest.raises(AttributeError):
        optics.NoSuchName  # noqa: B018
