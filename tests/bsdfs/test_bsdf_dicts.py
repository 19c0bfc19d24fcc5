"""Every model serialises to a plain dict: through JSON and back it is the same model and
gives the same values."""
import json

import numpy as np

import bsdflab as bl


def test_models_round_trip_through_json():
    models = [bl.Diffuse(0.3), bl.Diffuse([0.1, 0.2, 0.3], two_sided=True),
              bl.Diffuse({"type": "tabulated", "wavelengths": [400, 700], "values": [0.2, 0.9]}),
              bl.Conductor(material="Au"), bl.Conductor(eta=0.2, k=3.0), bl.Conductor(),
              bl.Dielectric(1.33, 1.0)]
    wi, wo = np.array([[0.0, 0.6, 0.8]]), np.array([[0.3, 0.0, np.sqrt(1 - 0.09)]])
    for m in models:
        d = json.loads(json.dumps(m.to_dict()))
        back = bl.from_dict(d)
        assert back == m
        assert np.array_equal(back.eval(wi, wo), m.eval(wi, wo))
