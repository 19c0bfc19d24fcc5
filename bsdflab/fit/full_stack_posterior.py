"""The log posterior of a full-model structure fit (bsdflab.fit.full_stack_config): one
structure, one or more datasets of gonio rows, each through its own instrument
(``<dataset>.scale`` or per-series scales, ``<dataset>.background``,
``<dataset>.angle_offset_deg``, ``.acceptance_deg``, ``.bandwidth_nm``):

    reported = scale * <pi f(structure)> + background

where <...> is the mean over the instrument's quadrature (the sample tilted by the angle
offset, the illumination cone, the slit: bsdflab.fit.gonio_instrument). All datasets' rows
go through one forward model (one emulator grid when solver parameters or the
quadrature's terms are free: the structure is shared; the terms are emulator axes as the
structure's are), then each dataset's scale and background apply to its rows.
Same interface as bsdflab.fit.stack_posterior.StackPosterior (a study and the sampler run it).
"""

from __future__ import annotations

import numpy as np

from bsdflab.fit.emulator import EmulatedForward, prior_box
from bsdflab.fit.full_stack_config import FullStackConfig
from bsdflab.fit.full_stack_forward import StructureSolverForward
from bsdflab.fit.gonio_instrument import TERMS
from bsdflab.fit.posterior import GaussianPosterior
from bsdflab.fit.stack_posterior import bind, concatenate

MODELLED = ("scale", "background", *TERMS)


class FullStackPosterior(GaussianPosterior):
    def __init__(self, datasets, config: FullStackConfig):
        datasets = list(datasets)
        if len(datasets) != len(config.datasets):
            raise ValueError(f"the config names {len(config.datasets)} dataset(s), got {len(datasets)}")
        self.datasets, self.stack = datasets, config
        domains, priors = bind(self, config, datasets, MODELLED)
        names = self.config.names
        self.dataset = concatenate(datasets, [spec.name for spec in config.datasets])
        self._slices = np.cumsum([0, *(len(d) for d in datasets)])
        m = config.model
        instruments, on = [], set()
        for spec, a, b in zip(config.datasets, self._slices[:-1], self._slices[1:]):
            instruments.append((int(a), int(b), {t: spec.prefix(t) for t in TERMS}))
            on |= {t for t in TERMS if t in spec.instrument.priors or spec.instrument.fixed.get(t, 0.0) != 0.0}
        solver = StructureSolverForward(
            self.dataset,
            config.structure,
            names,
            domains,
            m.nodes,
            m.orders,
            instruments,
            on,
            (m.bandwidth_nodes, m.cone_nodes, m.cone_azimuths),
        )
        # the emulator's axes: the free structure parameters and the free quadrature terms
        own = {p.name for p in config.structure.parameters()}
        own |= {spec.prefix(t) for spec in config.datasets for t in TERMS}
        solver_free = [n for n in self.free if n in own]
        if m.emulator_nodes and solver_free:
            boxes = {n: prior_box(n, priors[n], domains[n]) for n in solver_free}
            self.model = EmulatedForward(
                self.dataset, m, self._base, boxes, m.emulator_checks, config.sampler.seed, solver=solver, names=names
            )
        else:
            self.model = solver
        self.solver = solver
        self.evaluations = 0

    def named(self, x) -> dict[str, np.ndarray]:
        full = self.full(x)
        return {n: full[:, i] for i, n in enumerate(self.config.names)}

    def _model_values(self, full: np.ndarray) -> np.ndarray:
        inside = np.all(
            np.isfinite(full) & np.where(self._lo_open, full > self._lo, full >= self._lo) & (full <= self._hi), axis=1
        )
        out = np.full((len(full), len(self.dataset)), np.nan)
        if not np.any(inside):
            return out
        f = full[inside]
        y = self.model.evaluate(f)
        for spec, per, a, b in zip(self.stack.datasets, self._series, self._slices[:-1], self._slices[1:]):
            if per:
                scale = np.column_stack([f[:, self.col[spec.prefix(n)]] for n in per[0]])[:, per[1]]
            else:
                scale = f[:, self.col[spec.prefix("scale")]][:, None]
            y[:, a:b] = scale * y[:, a:b] + f[:, self.col[spec.prefix("background")]][:, None]
        out[inside] = y
        return out

    def material_dict(self, x) -> dict:
        """The Layered model dict of one free parameter vector (what material.json holds)."""
        return self.solver.model_dict(self.full(x)[0])

    def summary_extra(self) -> dict:
        """The emulator's measured error (summary.json), where there is one."""
        if not isinstance(self.model, EmulatedForward):
            return {"emulator": None}
        return {
            "emulator": {
                "solves": self.model.solves,
                "max_relative_error": self.model.max_relative_error,
                "max_error_sigma": self.model.max_error_sigma,
            }
        }
