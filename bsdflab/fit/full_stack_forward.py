"""The full model of a [structure] (bsdflab.fit.full_structure): each parameter set becomes
its ``Layered`` model dict (``FullStructure.model_dict``, what the study writes as
material.json) and is solved by adding-doubling (bsdflab.solvers.solve) at the dataset's
wavelengths; rows as the snake's full model (bsdflab.fit.full_forward: ``brdf`` and
``diffuse`` rows give pi f, ``total`` rows the directional-hemispherical reflectance,
bsdflab.fit.hemispherical). What lies below the top is solved once and reused while only
the top changes (``Solution.with_model``), as there.

The instrument's angle offset, acceptance cone and slit (bsdflab.fit.gonio_instrument) are
parameters of these vectors too (each dataset's own, by row): with any of them on, every
row is the mean of pi f over its quadrature nodes, all rows and nodes in one solve (at the
slit's wavelengths) and one ``Solution.eval``.
"""

from __future__ import annotations

import numpy as np

from bsdflab.bsdfs import from_dict
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.forward import parameter_sets
from bsdflab.fit.full_forward import BelowTopSolutions, RowPairs, SolveCounts, row_directions
from bsdflab.fit.full_structure import FullStructure
from bsdflab.fit.gonio_instrument import TERMS, GonioQuadrature
from bsdflab.fit.stack_forward import BANDWIDTH_NODES, CONE_AZIMUTHS, CONE_NODES


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
    instruments : sequence of (start, stop, {term: name})
        Rows start:stop read the instrument terms (``angle_offset_deg``, ``acceptance_deg``,
        ``bandwidth_nm``) from these columns of the vectors; none: every term off.
    on : set of str
        The terms that may be non-zero (the others take one quadrature node).
    quadrature : (bandwidth_nodes, cone_nodes, cone_azimuths), the smooth model's sizes
    """

    def __init__(
        self,
        dataset: Dataset,
        structure: FullStructure,
        names,
        domains,
        nodes: int = 16,
        orders: int = 0,
        instruments=(),
        on=frozenset(),
        quadrature=(BANDWIDTH_NODES, CONE_NODES, CONE_AZIMUTHS),
    ):
        self.dataset, self.structure = dataset, structure
        self.names = tuple(names)
        self._own = [p.name for p in structure.parameters()]
        missing = set(self._own) - set(self.names)
        if missing:
            raise ValueError(f"the parameter vectors lack the structure's {', '.join(sorted(missing))}")
        self._cols = [self.names.index(n) for n in self._own]
        self._domains = [domains[n] for n in self._own]
        self.nodes, self.orders = nodes, orders
        self._rows = RowPairs(dataset)
        self.wavelengths = self._rows.wavelengths
        self._solutions = BelowTopSolutions(self.wavelengths, nodes, orders)
        self._terms = np.zeros((len(TERMS), self.rows), dtype=int)  # column of each row's term, -1: off
        self._terms[:] = -1
        instrument_names = []
        for start, stop, cols in instruments:
            for t, term in enumerate(TERMS):
                if term in on and term in cols:
                    self._terms[t, start:stop] = self.names.index(cols[term])
                    instrument_names.append(cols[term])
        # the instrument's terms reuse the whole solve (offset, cone) or what lies below (slit)
        self.top_names = (*structure.top_names(), *instrument_names)
        self.quadrature = None
        if instrument_names:
            on = {TERMS[t] for t in range(len(TERMS)) if np.any(self._terms[t] >= 0)}
            self.quadrature = GonioQuadrature(
                *row_directions(dataset),
                dataset.wavelength_nm,
                "acceptance_deg" in on,
                "bandwidth_nm" in on,
                *quadrature,
                total=dataset.geometry == GEOMETRIES.index("total"),
            )

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
            model = from_dict(self.structure.model_dict(v))
            if self.quadrature is None:
                return self._rows.pi_f(self._solutions(model))
            vec = np.asarray(vector, float)
            offset, acceptance, bandwidth = (np.where(c >= 0, vec[np.maximum(c, 0)], 0.0) for c in self._terms)
            return self.quadrature.pi_f(lambda waves: self._solutions(model, waves), offset, acceptance, bandwidth)
        except ValueError:  # indices that do not chain, an index ratio outside the solver's range
            return np.full(self.rows, np.nan)

    def evaluate(self, full) -> np.ndarray:
        t, single = parameter_sets("values", full, self.names)
        out = np.array([self.predict_one(row) for row in t])
        return out[0] if single else out
