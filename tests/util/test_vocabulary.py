"""Issue 34's one vocabulary: the new names work silently, the old ones still work and say
(FutureWarning) what to write instead (bsdflab/util/deprecation.py)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import bsdflab as bl
from bsdflab import optics
from bsdflab.optics import Cauchy, Constant, FilmLayer, Tabulated, dispersion_from_dict
from bsdflab.oracles import _ad_operators

UP = np.array([[0.0, 0.0, 1.0]])
TILTED = np.array([[0.3, 0.0, np.sqrt(1 - 0.09)]])


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


@pytest.mark.parametrize("model", [Constant(1.8, 0.1), Cauchy(1.532, 5890.0), Tabulated([400, 700], [1.5, 1.4])])
def test_dispersion_dicts_are_tagged_type_and_old_model_tags_read(model):
    d = model.to_dict()
    assert d["type"] == model.type_name and "model" not in d
    assert silently(lambda: dispersion_from_dict(d)) == model
    old = {("model" if k == "type" else k): v for k, v in d.items()}
    with pytest.warns(FutureWarning, match="'model' is deprecated: it is now called 'type'"):
        assert dispersion_from_dict(old) == model
    with pytest.raises(ValueError, match="both 'type' and its old name 'model'"):
        dispersion_from_dict({**d, "model": d["type"]})


def test_a_stored_model_dict_with_old_dispersion_tags_still_builds():
    """A film material written before issue 34 (e.g. inside a stored table's model): it
    reads with a warning, and writes back in the new form."""
    new = bl.Dielectric(1.5, 1.0, film=[{"material": Cauchy(1.532, 5890.0), "thickness_nm": 400.0}]).to_dict()
    assert new["film"][0]["material"]["type"] == "cauchy"
    old = {**new, "film": [{"material": {"model": "cauchy", "A": 1.532, "B": 5890.0, "C": 0.0}, "thickness_nm": 400.0}]}
    with pytest.warns(FutureWarning, match="dispersion dict key 'model'"):
        assert bl.from_dict(old).to_dict() == new


def test_thickness_keyword_is_thickness_nm():
    coat = bl.RoughDielectric(0.3, 1.5, 1.0, film=[{"material": 1.8, "thickness_nm": 300.0}])
    new = silently(lambda: coat.eval(UP, UP, thickness_nm=[320.0]))
    with pytest.warns(FutureWarning, match="keyword 'thickness' is deprecated: it is now called 'thickness_nm'"):
        old = coat.eval(UP, UP, thickness=[320.0])
    np.testing.assert_array_equal(old, new)
    # the keyword changes the answer (a film 300 -> 320 nm shifts its colour), so it is passed on
    assert not np.array_equal(new, coat.eval(UP, UP))
    with pytest.warns(FutureWarning, match="thickness_nm"):
        old = coat.pdf(TILTED, UP, thickness=[320.0])
    np.testing.assert_array_equal(old, coat.pdf(TILTED, UP, thickness_nm=[320.0]))
    with pytest.warns(FutureWarning, match="thickness_nm"):
        old = coat.sample(TILTED, thickness=[320.0])
    np.testing.assert_array_equal(old.weight, coat.sample(TILTED, thickness_nm=[320.0]).weight)
    with pytest.raises(ValueError, match="pass thickness_nm= only"):
        coat.eval(UP, UP, thickness=[320.0], thickness_nm=[320.0])
    with pytest.raises(ValueError, match="thickness_nm"):
        coat.eval(UP, UP, thickness_nm=[-1.0])


def test_layered_and_slices_take_thickness_nm():
    from bsdflab.presets import preset
    from bsdflab.slices import evaluate

    snake = preset("xenopeltis", samples=64)
    kw = {"wavelengths": [550.0], "samples": 64, "seed": 1}
    new = silently(lambda: snake.estimate(TILTED, TILTED, thickness_nm=300.0, **kw))
    with pytest.warns(FutureWarning, match="thickness_nm"):
        old = snake.estimate(TILTED, TILTED, thickness=300.0, **kw)
    np.testing.assert_array_equal(old.value, new.value)
    with pytest.warns(FutureWarning, match="thickness_nm"):
        old = snake.eval_with_error(TILTED, TILTED, thickness=300.0, **kw)
    np.testing.assert_array_equal(old[0], new.value)
    with pytest.warns(FutureWarning, match="thickness_nm"):
        old = evaluate(snake, TILTED, TILTED, thickness=300.0, **kw)
    np.testing.assert_array_equal(old.values, new.value)
    with pytest.warns(FutureWarning, match="thickness_nm"):
        old = snake.delta_reflectance(UP, wavelengths=[550.0], thickness=300.0)
    np.testing.assert_array_equal(old, snake.delta_reflectance(UP, wavelengths=[550.0], thickness_nm=300.0))


def test_type_checks_are_isinstance_and_channels_are_real_wavelengths():
    """A layered core is never 'spectrally flat' (stochastic), found by isinstance, not by its
    class name; a render Diffuse's R, G, B channels carry real wavelengths, not [1, 2, 3]."""
    from bsdflab.bsdfs.base import _spectrally_flat
    from bsdflab.spectra import THREE_WAVELENGTHS_NM

    wl = np.array([450.0, 550.0, 650.0])
    grey = bl.Layered([bl.Dielectric(1.5, 1.0)], [bl.Slab(thickness_um=0.0)], bl.Diffuse(0.8), samples=16)
    assert not _spectrally_flat(grey._core(wl))  # its channels agree, yet it is stochastic
    assert _spectrally_flat(bl.Dielectric(1.5, 1.0)._core(wl))
    core, P = bl.Diffuse(0.3).render_core()
    assert P is None and list(core.wavelengths) == list(THREE_WAVELENGTHS_NM)
