"""A Chebyshev emulator of the full model's solver over the prior box: the fit's forward
model when the full model has free parameters (docs/fit.md, "The full model").

One adding-doubling solve costs ~0.3-1 s at a handful of wavelengths (the rough top's
product integration dominates), far too much for the 10^4-10^5 evaluations of an MCMC
run. The emulator solves once per node of a tensor Chebyshev grid over the free solver
parameters (the box where the prior has all but 2e-4 of its mass per parameter; log scale
for roughness and the slab coefficients) and interpolates log(pi f) of every row
(barycentric Lagrange interpolation, exact at the nodes, converging geometrically for the
smooth dependence on roughness, scattering and index; film thicknesses oscillate and need
more nodes). Outside the box it returns NaN (posterior zero: the truncation is stated).

The base albedo rho needs no nodes: with a Lambertian base the stack's response is exactly
y(rho) = (a + b rho) / (1 - c rho) for every row (the base's operator has rank one, so the
multiple reflections between base and stack form a geometric series; c is the stack's
albedo from below). Three solves at rho = ALBEDO_NODES give a, b, c at each node, and the
emulator interpolates log y at those three albedos and solves for a, b, c per row: exact
in rho (checked to 2e-16 against a fourth solve).

``checks`` direct solves at random points of the box measure the emulator's error
(``max_relative_error``, and ``max_error_sigma`` in units of the rows' sigma); a study
records both.
"""
from __future__ import annotations

import contextvars
import itertools
import math

import numpy as np

from bsdflab.fit.config import ModelSettings
from bsdflab.fit.data import Dataset
from bsdflab.fit.forward import parameter_sets
from bsdflab.fit.full_forward import SolverForwardModel
from bsdflab.fit.parameters import ALL_NAMES, parameter
from bsdflab.util.progress import report_progress, stop_if_cancelled

ALBEDO_NODES = (0.2, 0.5, 0.8)
# a study sets this around building its posterior: a progress bar over the grid's solves
SHOW_PROGRESS: contextvars.ContextVar[bool] = contextvars.ContextVar("bsdflab_fit_emulator_progress", default=False)
LOG_SCALE = ("roughness", "sigma_s", "pigment_absorption", "slab_thickness_um")
TAIL = 1e-4
TOP_NAMES = ("roughness", "film_thickness_nm", "film_ior", "film_cauchy_b", "platelet_nm", "gap_nm", "gap_ior",
             "exterior_ior")        # prior mass left out of the box on each side of an unbounded prior


def prior_box(name: str, prior, domain=None) -> tuple[float, float]:
    """The emulator's range of a parameter: a uniform prior's bounds, else its TAIL and 1 - TAIL
    quantiles; both clipped to the model's domain (``domain``: a Parameter, else the snake's)."""
    p = domain or parameter(name)
    lo, hi = prior.support() if prior.kind == "uniform" else (float(prior.ppf(TAIL)), float(prior.ppf(1 - TAIL)))
    lo, hi = max(lo, p.lo), min(hi, p.hi)
    if not lo < hi:
        raise ValueError(f"parameter {name!r}: its prior {prior.describe()} has no mass inside the model's "
                         f"domain [{p.lo:g}, {p.hi:g}]")
    return lo, hi


class _Axis:
    """Chebyshev nodes of the first kind on [lo, hi] (log-spaced for LOG_SCALE names) with
    barycentric weights."""

    def __init__(self, name: str, lo: float, hi: float, n: int):
        self.name, self.lo, self.hi, self.n = name, lo, hi, n
        self.log = name in LOG_SCALE and lo > 0
        self.a, self.b = (math.log(lo), math.log(hi)) if self.log else (lo, hi)
        j = np.arange(n)
        t = np.cos(np.pi * (j + 0.5) / n)[::-1]
        self.u = self.a + (self.b - self.a) * (t + 1) / 2           # node coordinates
        self.nodes = np.exp(self.u) if self.log else self.u            # parameter values
        self.w = ((-1.0) ** j * np.sin(np.pi * (j + 0.5) / n))[::-1]

    def basis(self, x: np.ndarray) -> np.ndarray:
        """Lagrange basis (P, n) at parameter values x (P,); rows outside the box are NaN."""
        inside = (x >= self.lo - 1e-12 * abs(self.lo)) & (x <= self.hi + 1e-12 * abs(self.hi))
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.log(np.where(x > 0, x, np.nan)) if self.log else x
            d = u[:, None] - self.u[None, :]
            exact = d == 0
            q = self.w[None, :] / d
            out = q / np.sum(q, axis=1, keepdims=True)
        hit = np.any(exact, axis=1)
        out[hit] = exact[hit].astype(float)
        out[~inside] = np.nan
        return out


class EmulatedForward:
    """The full model's observables (P, rows) for full parameter vectors, interpolated from
    solves on a Chebyshev grid over ``boxes``.

    Parameters
    ----------
    dataset : Dataset
    model : ModelSettings
        kind "full"; ``emulator_nodes`` nodes per free parameter.
    base : array (len(ALL_NAMES),)
        The fixed values (free ones are ignored).
    boxes : dict name -> (lo, hi)
        The free solver parameters and their ranges (base_albedo among them or not).
    checks : int
        Direct solves at random points of the box that measure the emulator's error.
    solver, names
        Another solver (``evaluate(full)`` of vectors in ``names`` order, optionally
        ``top_names``; a Lambertian base's albedo named base_albedo) and its parameter
        names: the full model of a [structure] (bsdflab.fit.full_stack_forward). Default:
        the snake's full model over ALL_NAMES.
    """

    def __init__(self, dataset: Dataset, model: ModelSettings, base, boxes: dict[str, tuple[float, float]],
                 checks: int = 0, seed: int = 0, solver=None, names=ALL_NAMES):
        self.solver = SolverForwardModel(dataset, model) if solver is None else solver
        self.names = tuple(names)
        self.dataset, self.base = dataset, np.asarray(base, float)
        self.albedo_free = "base_albedo" in boxes
        # the grid loop varies the last axis fastest: the top's parameters there reuse the
        # solution below the top (SolverForwardModel's cache)
        top = getattr(self.solver, "top_names", TOP_NAMES)
        names = sorted((n for n in boxes if n != "base_albedo"), key=lambda n: n in top)
        self.axes = [_Axis(n, *boxes[n], model.emulator_nodes) for n in names]
        self.albedo_box = boxes.get("base_albedo")
        self._cols = [self.names.index(a.name) for a in self.axes]
        self._albedo_col = self.names.index("base_albedo") if "base_albedo" in self.names else None
        albedos = (ALBEDO_NODES if self.albedo_free else
                   (float(self.base[self._albedo_col]) if self._albedo_col is not None else math.nan,))
        shape = tuple(a.n for a in self.axes)
        grid = np.empty((len(albedos), *shape, len(dataset)))
        nodes = itertools.product(*(range(n) for n in shape))
        if SHOW_PROGRESS.get():
            from tqdm import tqdm

            nodes = tqdm(nodes, total=math.prod(shape), desc="emulator solves", unit="node", leave=False)
        total = math.prod(shape)
        for done, idx in enumerate(nodes):
            report_progress("emulator", done / total)
            stop_if_cancelled("the emulator build")
            for k, rho in enumerate(albedos):
                v = self.base.copy()
                v[self._cols] = [a.nodes[i] for a, i in zip(self.axes, idx)]
                if self._albedo_col is not None:
                    v[self._albedo_col] = rho
                y = self.solver.evaluate(v)
                if not np.all(y > 0):
                    raise ValueError(f"the solver gave a non-positive or undefined value at the emulator node "
                                     f"{dict(zip([a.name for a in self.axes], v[self._cols]))}, base_albedo {rho}: "
                                     "narrow the prior")
                grid[(k, *idx)] = np.log(y)
        self._grid = grid
        self.solves = grid.size // len(dataset)
        self.max_relative_error = self.max_error_sigma = None
        if checks:
            self._check(checks, seed)

    @property
    def rows(self) -> int:
        return len(self.dataset)

    def _interpolate(self, full: np.ndarray) -> np.ndarray:
        """log y at the albedo nodes: (albedos, P, rows)."""
        g = np.moveaxis(self._grid, 0, -2)               # (*shape, albedos, rows)
        if not self.axes:
            return np.broadcast_to(g[:, None, :], (g.shape[0], len(full), g.shape[1]))
        out = np.einsum("pn,n...->p...", self.axes[0].basis(full[:, self._cols[0]]), g)
        for j, axis in enumerate(self.axes[1:], 1):
            out = np.einsum("pn,pn...->p...", axis.basis(full[:, self._cols[j]]), out)
        return np.moveaxis(out, 1, 0)                    # (albedos, P, rows)

    def evaluate(self, full) -> np.ndarray:
        """Model values (P, rows) for full vectors (P, len(ALL_NAMES)) or (rows,) for one."""
        t, single = parameter_sets("values", full, self.names)
        y = np.exp(self._interpolate(t))                 # (albedos, P, rows)
        if self.albedo_free:
            rho = t[:, self._albedo_col][:, None]
            r = np.asarray(ALBEDO_NODES)
            # y_k = a + b r_k + c r_k y_k for the three nodes -> (a, b, c) per (set, row)
            m = np.stack([np.ones_like(y), np.broadcast_to(r[:, None, None], y.shape), r[:, None, None] * y], -1)
            m = np.moveaxis(m, 0, -2)                    # (P, rows, 3, 3)
            coef = np.linalg.solve(m, np.moveaxis(y, 0, -1)[..., None])[..., 0]
            lo, hi = self.albedo_box
            with np.errstate(invalid="ignore"):
                val = (coef[..., 0] + coef[..., 1] * rho) / (1 - coef[..., 2] * rho)
            val[~((rho[:, 0] >= lo) & (rho[:, 0] <= hi))] = np.nan
        else:
            val = y[0]
        return val[0] if single else val

    def _check(self, n: int, seed: int) -> None:
        rng = np.random.default_rng(seed)
        pts = np.repeat(self.base[None, :], n, axis=0)
        for a, col in zip(self.axes, self._cols):
            u = rng.uniform(a.a, a.b, n)
            pts[:, col] = np.exp(u) if a.log else u
        if self.albedo_free:
            pts[:, self._albedo_col] = rng.uniform(*self.albedo_box, n)
        direct = self.solver.evaluate(pts)
        emulated = self.evaluate(pts)
        self.max_relative_error = float(np.max(np.abs(emulated / direct - 1)))
        self.max_error_sigma = float(np.max(np.abs(emulated - direct) / self.dataset.sigma[None, :]))
