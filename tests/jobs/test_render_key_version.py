"""A render's key holds the core's estimator version: a layered material renders through
PFMC's walks (or tables they made), so after a version bump (e.g. 8: a per-query film
thickness is the top film's alone, which changes a scale-textured stack with a filmed base)
the same request must render anew. Before, the key held the request, the kind and the
package version only, and the store served the image the old walks made."""

from __future__ import annotations

from bsdflab import _core
from bsdflab.jobs import render as render_job

BASE = {"scene": "furnace", "width": 8, "height": 8, "spp": 1}


def test_the_render_key_changes_with_the_estimator_version(monkeypatch):
    request = render_job.normalise(dict(BASE))
    now = render_job.key(request)
    assert now == render_job.key(render_job.normalise(dict(BASE)))  # a function of the request
    monkeypatch.setattr(_core, "estimator_version", int(_core.estimator_version) + 1, raising=False)
    assert render_job.key(request) != now
