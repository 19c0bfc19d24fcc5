"""colour-science's sensor model and RGB basis on the renderer's default grid, precomputed.

Every material a render builds needs ``srgb_weights`` on DEFAULT_WAVELENGTHS, and
``import colour`` costs about 2.4 CPU-s (its package imports its plotting, matplotlib,
scipy and pandas) in every process that renders. The arrays for that one grid and the
default ColourSpace are stored next to this file, as colour-science computes them; any
other grid or space is computed by colour-science at run time.

Regenerate after a colour-science upgrade (tests/optics/test_colour_precomputed.py fails
until then): ``python -c "from bsdflab.spectra.colour_weights import store_precomputed; store_precomputed()"``.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from bsdflab.spectra.grid import DEFAULT_WAVELENGTHS

PATH = Path(__file__).with_name("colour_default_grid.npz")
NAMES = ("wavelengths", "cmf", "illuminant", "xyz_to_rgb", "basis")


@lru_cache(maxsize=1)
def stored() -> dict[str, np.ndarray]:
    """The stored arrays (read-only), by NAMES."""
    with np.load(PATH) as f:
        arrays = {name: np.array(f[name]) for name in NAMES}
    for a in arrays.values():
        a.setflags(write=False)
    return arrays


def covers(grid: tuple[float, ...]) -> bool:
    """True when ``grid`` is exactly the stored grid."""
    return len(grid) == len(DEFAULT_WAVELENGTHS) and np.array_equal(np.asarray(grid), stored()["wavelengths"])


def write(arrays: dict[str, np.ndarray], path: Path = PATH) -> None:
    """Store ``arrays`` (by NAMES) as the file, atomically."""
    from bsdflab.util.files import write_atomically

    def write_file(tmp: str) -> None:
        with open(tmp, "wb") as f:
            np.savez(f, **{name: arrays[name] for name in NAMES})

    write_atomically(path, write_file, suffix=".npz")
