"""bsdflab.reference: cross-checks of bsdflab models against Mitsuba 3.

``python -m bsdflab.reference`` prints the BSDF-level comparison reports
(smooth and rough materials, eval / pdf / sample, both sides). The module ships inside the
wheel as ``bsdflab.reference`` (see pyproject.toml, wheel.packages).
"""
