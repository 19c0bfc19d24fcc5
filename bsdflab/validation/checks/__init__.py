"""The registered checks, one module per model family (importing registers them)."""
from bsdflab.validation.checks import approximations, basic, films, layered, renderer, rough, tables  # noqa: F401
