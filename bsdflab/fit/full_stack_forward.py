"""The full model of a [structure] (bsdflab.fit.full_structure): each parameter set becomes
its ``Layered`` model dict (``FullStructure.model_dict``, what the study writes as
material.json) and is solved by adding-doubling (bsdflab.solvers.solve) at the dataset's
wavelengths; rows as the snake's full model (bsdflab.fit.full_forward: ``brdf`` and
``diffuse`` rows give pi f). What lies below the top is solved once and reused while only
the top changes (``Solution.with_model``), as there.
"""

from __future__ import annotations

import numpy as np

from bsdflab.bsdfs import from_dict
from bsdflab.fit.data import Dataset
from bsdflab.fit.forward import parameter_sets
from bsdflab.fit.full_forward import BelowTopSolutions, RowPairs, SolveCounts
from bsdflab.fit.full_structure import FullStructure


class StructureSolverForward(SolveCounts):
    """pi f (P, rows) of ``dataset``'s brdf/diffuse rows for parameter vectors (P, len(names)).

    Parameters
    ----------
    dataset : Dataset
    structure : FullStructure
    names : sequence of str
        The vectors' columns; every parameter of ``structure`` among them (others ignored).
    domains : dict name -> Parameter
        Where the model is defined (outside: NaN).
    nodes, orders : the solver's (orders 0: automatic)
    """

    def __init__(self, dataset: Dataset, structure: FullStructure, names, domains, nodes: int = 16, orders: int = 0):
        self.dataset, self.structure = dataset, structure
        self.names = tuple(names)
        self._own = [p.name for p in structure.parameters()]
        missing = set(self._own) - set(self.names)
        if missing:
            raise ValueError(f"the parameter vectors lack the structure's {', '.join(sorted(missing))}")
        self._cols = [self.names.index(n) for n in self._own]
        self._domains = [domains[n] for n in self._own]
        self.top_names = structure.top_names()
        self.nodes, self.orders = nodes, orders
        self._rows = RowPairs(dataset)
        self.wavelengths = self._rows.wavelengths
        self._solutions = BelowTopSolutions(self.wavelengths, nodes, orders)

    @property
    def rows(self) -> int:
        return len(self.dataset)

    def values(self, vector) -> dict[str, float]:
        """The structure's parameters of one vector, by name."""
        v = np.asarray(vector, float)
        return {n: float(v[c]) for n, c in zip(self._own, self._cols)}

    def model_dict(self, vector, samples: int = 256) -> dict:
        return self.structure.model_dict(self.values(vector), samples)

    def predict_one(self, vector) -> np.ndarray:
        v = self.values(vector)
        inside = all((x > p.lo if p.lo_open else x >= p.lo) and x <= p.hi for x, p in zip(v.values(), self._domains))
        if not inside:
            return np.full(self.rows, np.nan)
        try:
            sol = self._solutions(from_dict(self.structure.model_dict(v)))
        except ValueError:  # indices that do not chain, an index ratio outside the solver's range
            return np.full(self.rows, np.nan)
        return self._rows.pi_f(sol)

    def evaluate(self, full) -> np.ndarray:
        t, single = parameter_sets("values", full, self.names)
        out = np.array([self.predict_one(row) for row in t])
        return out[0] if single else out
