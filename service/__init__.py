"""bsdflab.service: the HTTP API (FastAPI) over the Python API and bsdflab.jobs.

Ships inside the wheel as ``bsdflab.service`` (see pyproject.toml, wheel.packages); run it
with ``bsdflab serve``. ``create_app(Settings(...))`` builds the application; nothing here
computes physics (docs/service.md).
"""
from bsdflab.util.extras import require

require("fastapi", "service")  # before the app's own imports: a clear message when missing

from bsdflab.service.app import create_app  # noqa: E402
from bsdflab.service.settings import Settings  # noqa: E402

__all__ = ["Settings", "create_app"]
