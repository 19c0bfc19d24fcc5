"""Optional dependencies: import one, or fail with the extra that installs it.

The core (``pip install bsdflab``) evaluates, tabulates, renders and plots BSDFs; each use
beyond it is an extra of pyproject.toml:

==========  ===============================================  ==============================
extra       what it installs                                 what needs it
==========  ===============================================  ==============================
service     fastapi, uvicorn, pydantic(-settings), plotly    ``bsdflab serve``, bsdflab.service
dask        distributed                                      bsdflab.distributed, ``--cluster``
fit         emcee, dynesty, arviz, corner, h5netcdf,         bsdflab.fit, ``bsdflab fit``
            jcamp, avaread                                   (``fit import`` readers)
mitsuba     mitsuba, drjit, flip-evaluator                   bsdflab.reference, renderer checks
export      (the exporters' tools)                           bsdflab.export
denoise     pyoidn                                           ``bsdflab render --denoise``
all, test   every extra (test: and the test tools)           ``./dev.sh`` installs ``.[test]``
==========  ===============================================  ==============================
"""
from __future__ import annotations

import importlib
from types import ModuleType


def require(module: str, extra: str) -> ModuleType:
    """``import module``, or an ImportError that names the extra to install, e.g.
    ``pip install 'bsdflab[dask]'``."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        raise ImportError(f"{module} is not installed; it comes with bsdflab's {extra!r} extra: "
                          f"pip install 'bsdflab[{extra}]' ({e})") from e
