"""Interface models at the ends of their ranges: indices outside the physical range are
refused with a ValueError naming the parameter (they gave NaN before); the ends of the
documented ranges give finite eval, pdf and samples."""
from __future__ import annotations

import numpy as np
import pytest

import bsdflab as bl


@pytest.mark.parametrize("make, name", [
    (lambda: bl.Dielectric(int_ior=1e-200), "int_ior"),          # old: sampled NaN directions
    (lambda: bl.Dielectric(ext_ior=1e-320), "ext_ior"),          # old: infinite eta, NaN weight
    (lambda: bl.RoughDielectric(0.3, int_ior=1e200), "int_ior"),  # old: eval NaN
    (lambda: bl.Dielectric(int_ior=1e3, ext_ior=1.0), "int_ior / ext_ior"),
    (lambda: bl.Conductor(eta=1e-9, k=1.0), "eta"),
    (lambda: bl.Conductor(eta=1.0, k=1e9), "k"),
    (lambda: bl.Dielectric(film=[{"material": 1e39, "thickness_nm": 100}]), "material"),
    (lambda: bl.Dielectric(film=[{"material": 1.5, "thickness_nm": 1e308}]), "thickness_nm"),
])
def test_indices_outside_the_physical_range_are_refused(make, name):
    with pytest.raises(ValueError, match=name):
        make()


def test_accepted_extremes_stay_finite():
    # the ends of the documented ranges: every output finite
    for model in (bl.Dielectric(1e3, 1e3 / 100), bl.Dielectric(1e-3, 1e-3 * 100),
                  bl.RoughDielectric(0.3, 2.0, 1e-3 * 100), bl.RoughDielectric(4.0, 1e3, 10.0),
                  bl.Conductor(eta=1e-3, k=1e3), bl.RoughConductor(1e-4, eta=1e3, k=0.0)):
        wi = np.array([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8], [0.999, 0.0, np.sqrt(1 - 0.999**2)]])
        s = model.sample(wi, seed=1)
        for a in (model.eval(wi, wi[::-1]), model.pdf(wi, wi[::-1]), s.weight, s.wo, s.pdf):
            assert np.all(np.isfinite(a)), model
