"""Small valid tables for the table-file tests."""
from __future__ import annotations

import numpy as np

from bsdflab.tables import TableData, TableGrid

MODEL = {"type": "diffuse", "reflectance": 0.5}
GRID = TableGrid(3, 5, 4)


def valid_table(stderr: float = 0.001) -> TableData:
    """A 3 x 5 x 4 RGB reflection table of MODEL: values 0.1, standard errors ``stderr``."""
    shape = (1, 1, 3, 5, 4, 3)
    return TableData(MODEL, GRID, ("reflection",), ("R", "G", "B"), False, np.full(shape, 0.1, np.float32),
                     np.full(shape, stderr, np.float32), np.ones(shape[:-1], np.int32), 0.01)
