"""bsdflab.service: the HTTP API (FastAPI) over the Python API.

Ships inside the wheel as ``bsdflab.service`` (see pyproject.toml, wheel.packages). The
application itself arrives with the service issue; nothing here computes physics.
"""
