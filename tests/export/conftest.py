"""Fixtures shared by the export tests."""
from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def film_blender_export(tmp_path_factory):
    """export(FILM, "blender") once for the session: (report, folder holding film.blend and the
    report's other files). The export is deterministic, and both Cycles cross-checks
    (test_export_cycles_crosscheck.py, test_export_cycles_render.py) test this same export:
    ~8 CPU-s (its fit and one bpy process) made once. Tests write their renders elsewhere."""
    from bsdflab.export import export
    from support.cycles_spheres import FILM

    folder = tmp_path_factory.mktemp("film_export")
    return export(FILM, "blender", str(folder / "film.blend")), folder
