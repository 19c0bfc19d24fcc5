"""The full model's forward model: parameter sets -> the rendered ``Layered`` model ->
the adding-doubling solver (bsdflab.solvers, docs/solvers.md) -> the dataset's observables.

Each parameter set becomes the model dict that the study writes as material.json
(``bsdflab.fit.material.material_dict``), and that dict's ``Layered`` model is solved at the
dataset's wavelengths: the fitted model IS the tabulated and rendered one (rough top with
its film or platelet stack, Henyey-Greenstein slab with spectral sigma_a and grey sigma_s,
Lambertian base). One solve per parameter set (a Python loop over sets; the solve itself
is threaded C++); the solution of what lies below the top is reused when only the top
changes (``Solution.with_model``: roughness, film), which makes fits with a fixed slab
several times cheaper.

Rows: ``brdf`` (and ``diffuse``, its in-plane special case) give the reflectance factor
pi f(theta_i, theta_o, phi), the rough top's own reflection included; ``total`` rows the
directional-hemispherical reflectance (integrating sphere, the top's reflection included:
bsdflab.fit.hemispherical, its own quadrature around the mirror direction). ``specular``
rows are not modelled (a rough top has no mirror beam): ValueError.

Geometry: the source lies at polar angle theta_i in the plane of incidence; phi is the
detector's azimuth measured from the mirror side (phi = 0: the plane of incidence on the
side away from the source, where the mirror direction lies; 180: back toward the source).
"""
from __future__ import annotations

import json
import warnings

import numpy as np

from bsdflab.bsdfs import from_dict
from bsdflab.fit.config import ModelSettings
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.forward import ForwardModel, parameter_sets
from bsdflab.fit.hemispherical import MAX_INCIDENCE_DEG, directional_albedo
from bsdflab.fit.material import material_dict
from bsdflab.fit.parameters import ALL_NAMES, FORWARD_NAMES, in_domain
from bsdflab.solvers import solve

CACHE = 64   # below-the-top solutions kept for reuse (an emulator grid varies the top fastest)


def row_directions(dataset: Dataset) -> tuple[np.ndarray, np.ndarray]:
    """(detector, source) unit directions (rows, 3) of brdf, diffuse and total rows (+z up;
    a total row's detector is the normal, unused: its value is the integral over all)."""
    g = dataset.geometry
    brdf, diffuse = g == GEOMETRIES.index("brdf"), g == GEOMETRIES.index("diffuse")
    bad = ~(brdf | diffuse | (g == GEOMETRIES.index("total")))
    if np.any(bad):
        i = int(np.argmax(bad))
        raise ValueError(f"row {i}: geometry {GEOMETRIES[g[i]]!r} is not modelled by the full model (a rough top "
                         "has no mirror beam); use brdf or total rows (or kind = 'smooth')")
    theta_o = np.radians(np.where(brdf, dataset.angle_out_deg, np.where(diffuse, np.abs(dataset.angle_out_deg), 0.0)))
    phi = np.radians(np.where(brdf, dataset.phi_deg, np.where(dataset.angle_out_deg >= 0, 0.0, 180.0)))
    ti = np.radians(dataset.angle_deg)
    source = np.column_stack([-np.sin(ti), np.zeros_like(ti), np.cos(ti)])
    detector = np.column_stack([np.sin(theta_o) * np.cos(phi), np.sin(theta_o) * np.sin(phi), np.cos(theta_o)])
    return detector, source


class RowPairs:
    """A dataset's rows as what a solution is evaluated at: brdf/diffuse rows as the distinct
    (wi, wo) pairs and wavelengths, and the pick that spreads pi f back over them; total rows
    as their distinct incidence cosines (bsdflab.fit.hemispherical)."""

    def __init__(self, dataset: Dataset):
        self.wavelengths, wl_index = np.unique(dataset.wavelength_nm, return_inverse=True)
        wl_index = wl_index.ravel()
        detector, source = row_directions(dataset)
        self.total = dataset.geometry == GEOMETRIES.index("total")
        gonio = ~self.total
        pairs, pair_index = np.unique(np.hstack([detector, source])[gonio], axis=0, return_inverse=True)
        self.wi, self.wo = np.ascontiguousarray(pairs[:, :3]), np.ascontiguousarray(pairs[:, 3:])
        self.pick = (pair_index.ravel(), wl_index[gonio])
        steep = self.total & (dataset.angle_deg > MAX_INCIDENCE_DEG)
        if np.any(steep):
            i = int(np.argmax(steep))
            raise ValueError(f"row {i}: a total row's angle_deg must be at most {MAX_INCIDENCE_DEG:g} "
                             f"(the hemispherical rule's range), got {dataset.angle_deg[i]:g}")
        self.mu, mu_index = np.unique(source[self.total, 2], return_inverse=True)
        self.total_pick = (mu_index.ravel(), wl_index[self.total])

    def pi_f(self, sol) -> np.ndarray:
        """pi f per brdf/diffuse row from a solution's f |cos theta_o| at the distinct pairs,
        the directional-hemispherical reflectance per total row."""
        out = np.empty(len(self.total))
        if len(self.wi):
            out[~self.total] = (np.pi * sol.eval(self.wi, self.wo) / self.wo[:, 2:3])[self.pick]
        if len(self.mu):
            out[self.total] = directional_albedo(sol, self.mu, self.wavelengths)[self.total_pick]
        return out


class BelowTopSolutions:
    """Adding-doubling solutions keyed by what lies below the top and the wavelengths: a model
    that differs from a cached one in its top only reuses that solve (``Solution.with_model``);
    at most CACHE kept. The same model at the same wavelengths as the last call (an
    instrument term changed, not the structure) returns the last solution itself."""

    def __init__(self, wavelengths, nodes: int, orders: int):
        self.wavelengths, self.nodes, self.orders = wavelengths, nodes, orders
        self._cache: dict[str, object] = {}
        self._last: tuple[str, object] | None = None
        self.solves = 0        # full solves (what lies below the top solved anew)
        self.top_solves = 0    # solves that reused the layers below the top

    def __call__(self, model, wavelengths=None):
        wavelengths = self.wavelengths if wavelengths is None else wavelengths
        d = model.to_dict()
        waves = np.asarray(wavelengths, float).tolist()
        whole = json.dumps([d, waves], sort_keys=True)
        if self._last is not None and self._last[0] == whole:
            return self._last[1]
        key = json.dumps([{**d, "interfaces": d["interfaces"][1:]}, waves], sort_keys=True)
        if key in self._cache:
            self.top_solves += 1
            sol = self._cache[key].with_model(model)
        else:
            with warnings.catch_warnings():
                # the solver raises the nodes to resolve the slab's phase function and says so;
                # in a fit that is expected for every parameter set (docs/fit.md)
                warnings.filterwarnings("ignore", message="adding-doubling: nodes raised", category=UserWarning)
                sol = solve(model, wavelengths=wavelengths, nodes=self.nodes, orders=self.orders or None)
            self.solves += 1
            if len(self._cache) >= CACHE:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = sol
        self._last = (whole, sol)
        return sol


class SolveCounts:
    """``solves`` and ``top_solves`` of a forward model's ``_solutions`` (BelowTopSolutions)."""

    @property
    def solves(self) -> int:
        return self._solutions.solves

    @property
    def top_solves(self) -> int:
        return self._solutions.top_solves


class SolverForwardModel(SolveCounts):
    """Observables (P, rows) of ``dataset`` for full parameter vectors (P, len(ALL_NAMES)).

    Parameters
    ----------
    dataset : Dataset
        brdf, diffuse and total rows (angles, wavelengths; the values are not used).
    model : ModelSettings
        kind "full": film, platelets, distribution, solver nodes (raised to the slab's
        ``nodes_for_g``) and orders (0: automatic).
    """

    def __init__(self, dataset: Dataset, model: ModelSettings):
        if model.kind != "full":
            raise ValueError(f"SolverForwardModel needs [model] kind = 'full', got {model.kind!r}")
        self.dataset, self.settings = dataset, model
        self._rows = RowPairs(dataset)
        self.wavelengths = self._rows.wavelengths
        self._names = model.names()
        self._solutions = BelowTopSolutions(self.wavelengths, model.nodes, model.orders)

    @property
    def rows(self) -> int:
        return len(self.dataset)

    def layered(self, values):
        """The ``Layered`` model of one full parameter vector (what material.json holds)."""
        return from_dict(material_dict(values, model=self.settings))

    def predict_one(self, values) -> np.ndarray:
        """pi f for every row of one full parameter vector (NaN outside the domain)."""
        v = dict(zip(ALL_NAMES, map(float, values)))
        if not all(in_domain(n, v[n]) for n in self._names) or v["substrate_ior"] <= v["exterior_ior"]:
            return np.full(self.rows, np.nan)
        try:
            sol = self._solutions(self.layered(v))
        except ValueError:
            return np.full(self.rows, np.nan)
        return self._rows.pi_f(sol)

    def evaluate(self, full) -> np.ndarray:
        """Model values (P, rows) for full parameter vectors (P, len(ALL_NAMES)), or (rows,)."""
        t, single = parameter_sets("values", full, ALL_NAMES)
        out = np.array([self.predict_one(row) for row in t])
        return out[0] if single else out


class SmoothForward:
    """The smooth C++ model behind the same interface (full vectors in, values out)."""

    def __init__(self, dataset: Dataset, model: ModelSettings):
        self.model = ForwardModel(dataset, model.thickness_nodes, model.angle_nodes)
        self._cols = np.array([ALL_NAMES.index(n) for n in FORWARD_NAMES])

    def evaluate(self, full) -> np.ndarray:
        return self.model.evaluate(np.asarray(full, dtype=np.float64)[..., self._cols])


def forward_model(dataset: Dataset, model: ModelSettings):
    """The forward model that ``model.kind`` names: ``evaluate(full)`` -> (P, rows)."""
    return SolverForwardModel(dataset, model) if model.kind == "full" else SmoothForward(dataset, model)
