"""The registered checks, one module per model family (importing registers them)."""
from bsdflab.validation.checks import (  # noqa: F401
    approximations,
    basic,
    coverage,
    cycles,
    export,
    films,
    fit,
    layered,
    measured,
    renderer,
    rough,
    service,
    solvers,
    tables,
)
