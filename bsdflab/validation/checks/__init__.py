"""The registered checks, one module per model family (importing registers them)."""
from . import approximations, basic, films, layered, renderer, rough, tables  # noqa: F401
