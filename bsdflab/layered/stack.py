"""`Layered`: a stack of interfaces, slabs and a base, evaluated by Position-Free Monte
Carlo in the C++ core (core/include/bsdflab/layered.h documents the estimator).

Stack order, top to bottom: interfaces[0], slabs[0], interfaces[1], slabs[1], ...,
slabs[-1], base. Interfaces are dielectric models (smooth or rough, with or without a thin
film); the base is any BSDF (Diffuse, Conductor, RoughConductor, or a Dielectric /
RoughDielectric to a medium below, which makes the stack transmissive). Indices must
chain: interface j's int_ior is the index of slab j and must equal the ext_ior of the
next interface (or of a base that has one).

eval() is a Monte Carlo estimate: `samples` random walks per direction pair, seeded from
(seed, wi, wo), so the same call gives the same answer. `estimate` also returns the
standard error and the number of walks whose contribution was not finite (counted, never
hidden: 0 for a sound model); `eval_with_error` returns the first two. The top interface's delta reflection (a smooth
top) is not part of eval: `delta_reflectance` gives it exactly, and `sample` returns it as a delta lobe.
`pdf` is the density with which `sample` returns wo (the top's own reflection exactly, the
walk's exits by an unbiased estimate seeded from (seed, wi, wo)), for multiple importance
sampling; `sample`'s weight is the walk's unbiased throughput.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF, from_dict
from bsdflab.bsdfs.dielectric import Dielectric
from bsdflab.bsdfs.rough import RoughDielectric
from bsdflab.layered.slab import Slab
from bsdflab.lobes import Lobe
from bsdflab.util import args as check
from bsdflab.util.deprecation import renamed_keywords

INTERFACE_TYPES = (Dielectric, RoughDielectric)
MAX_SLABS = 16
IOR_TOLERANCE = 1e-9
MAX_WALKS = 1 << 24
MAX_DEPTH = 1 << 16
PDF_SAMPLES = 1
# Default extra walks for the standard error of `estimate`, per walk of the value
# (core/include/bsdflab/walk_statistics.h; measured in docs/coverage.md).
ERROR_WALKS_PER_SAMPLE = 4
# The walk's estimators (core/include/bsdflab/layered.h, docs/estimators.md): "pfmc"
# (Guo et al.'s, as estimator version 5: the reference) and "pfmc2" (the default).
ESTIMATORS = {"pfmc": 0, "pfmc2": 1}
ESTIMATOR = "pfmc2"


@dataclass(frozen=True)
class Estimate:
    """A Monte Carlo estimate of eval for N direction pairs."""

    value: np.ndarray   # (N, C)
    stderr: np.ndarray  # (N, C) standard error (for colour output the bound sum_l |W_cl| sigma_l)
    nonfinite: int      # walks whose contribution was not finite (they count as 0)
    capped: int = 0     # walks cut by max_depth (truncated, so biased low; 0 for a sound model)


def _model(value, name: str) -> BSDF:
    if isinstance(value, BSDF):
        return value
    if isinstance(value, dict):
        return from_dict(value)
    raise ValueError(f"{name} must be a BSDF or a BSDF dict, got {value!r}")


def _interface_refusal(i: int, m) -> str:
    """Why ``m`` cannot be interface ``i``: a conductor is opaque, so as the top it hides the
    stack (the material is the conductor itself, with its film: docs/solvers.md,
    "Conductor tops") and below it is the stack's base."""
    kind = getattr(m, "type_name", type(m).__name__)
    must = f"interfaces[{i}] must be a dielectric or roughdielectric, got {kind!r}"
    if kind not in ("conductor", "roughconductor"):
        return must
    if i == 0:
        return (f"{must}: a conductor top is opaque and hides every layer below it, so the stack is the "
                f"conductor itself; use the {kind} model (with its film=[...] for a coated metal) as the material")
    return f"{must}: nothing passes a conductor, so it ends the stack: make it the base"


class Layered(BSDF):
    """A layered BSDF by Position-Free Monte Carlo (Guo, Hasan & Zhao 2018).

    Parameters
    ----------
    interfaces : list of Dielectric / RoughDielectric (or dicts), top first, >= 1
    slabs : list of Slab (or dicts), one below each interface
    base : BSDF or dict
        What lies below the last slab.
    samples : int in [1, 2^24]
        Random walks per eval() of one direction pair. Default 256.
    seed : int in [0, 2^64)
        Seed of the walks (combined with the directions). Default 0.
    max_depth : int in [1, 2^16]
        Events per walk before it is cut: a safety net. Russian roulette on the
        throughput ends walks without bias; a walk the cap cuts is truncated (biased
        low) and counted (``Estimate.capped``, ``capped_walks``). Default 2^16; the
        former default 256 cut walks in thick, bright slabs (-8.9 % at optical depth 10,
        single-scattering albedo 0.999, over a white base).
    pdf_samples : int in [0, 2^16]
        Walks of one ``pdf`` estimate (seeded from (seed, wi, wo), so ``pdf`` is a fixed
        function of the pair). ``pdf`` is the density with which ``sample`` returns wo:
        the top's own reflection exactly plus an unbiased estimate of the walk's exits
        through a rough outer boundary; through a smooth one, the estimated share of
        exits (smoothed, never 0) as a cosine lobe over the directions it refracts into
        (docs/estimators.md). 0: estimator version 4's
        deterministic approximation (for comparisons). Default 1 (bench/bench_layered_pdf.py:
        more walks cost more render time than their MIS weights save on the snake).
    estimator : {"pfmc2", "pfmc"}
        The walk. "pfmc2" (default): four walks share one light chain where it is
        deterministic (smooth boundaries on its way), and thick bright slabs (albedo of the least
        absorbed channel >= 0.95, optical depth >= 1) draw flights by their smallest
        extinction, so spectral weights stay <= 1 (no heavy tails when channels differ
        wildly). "pfmc": Guo et al.'s estimator as estimator version 5, the reference.
        Efficiency against version 5's core: 4.1x on the snake (all of it from cheaper
        thin films and vectorised exp, which pfmc shares: there pfmc2 walks as pfmc),
        1.05-1.58x on stacks with smooth boundaries or bright slabs (docs/performance.md,
        docs/estimators.md).
    """

    type_name = "layered"

    def __init__(self, interfaces, slabs, base, samples: int = 256, seed: int = 0,
                 max_depth: int = MAX_DEPTH, pdf_samples: int = PDF_SAMPLES, estimator: str = ESTIMATOR):
        super().__init__()
        if not isinstance(interfaces, (list, tuple)) or not interfaces:
            raise ValueError("interfaces must be a non-empty list (top first)")
        if not isinstance(slabs, (list, tuple)) or len(slabs) != len(interfaces):
            raise ValueError(f"slabs must be a list with one slab per interface "
                             f"({len(interfaces)}), got {slabs!r}")
        if len(slabs) > MAX_SLABS:
            raise ValueError(f"at most {MAX_SLABS} slabs are supported, got {len(slabs)}")
        self.interfaces = tuple(_model(m, f"interfaces[{i}]") for i, m in enumerate(interfaces))
        for i, m in enumerate(self.interfaces):
            if not isinstance(m, INTERFACE_TYPES):
                raise ValueError(_interface_refusal(i, m))
        self.slabs = tuple(Slab.coerce(s, i) for i, s in enumerate(slabs))
        self.base = _model(base, "base")
        if isinstance(self.base, Layered):
            raise ValueError("base must not itself be layered: list its layers in this stack")
        self.samples = _positive_int("samples", samples)
        self.seed = check.seed(seed)
        self.max_depth = _positive_int("max_depth", max_depth)
        self.pdf_samples = check.integer("pdf_samples", pdf_samples, 0, MAX_DEPTH)
        if not isinstance(estimator, str) or estimator not in ESTIMATORS:
            raise ValueError(f"estimator must be one of {', '.join(map(repr, ESTIMATORS))}, "
                             f"got {check.brief(estimator)}")
        self.estimator = estimator
        self._check_indices()

    def _check_indices(self) -> None:
        below = [getattr(m, "ext_ior", None) for m in self.interfaces[1:]]
        below.append(getattr(self.base, "ext_ior", None))
        for j, (upper, lower) in enumerate(zip(self.interfaces, below)):
            if lower is not None and abs(upper.int_ior - lower) > IOR_TOLERANCE * upper.int_ior:
                who = f"interfaces[{j + 1}]" if j + 1 < len(self.interfaces) else "base"
                raise ValueError(f"slab {j} has index {upper.int_ior} (interfaces[{j}].int_ior) "
                                 f"but {who}.ext_ior is {lower}: they must be equal")

    # -- core -----------------------------------------------------------------------------
    def _build(self, wavelengths: np.ndarray, nee: bool = True):
        wl = np.asarray(wavelengths, dtype=np.float64)
        boundaries = [m._core(wl) for m in (*self.interfaces, self.base)]
        options = _core.LayeredOptions(samples=self.samples, seed=self.seed, max_depth=self.max_depth, nee=nee,
                                       pdf_samples=self.pdf_samples, estimator=ESTIMATORS[self.estimator])
        return _core.LayeredBSDF(
            list(wl), boundaries, thickness_um=[s.thickness_um for s in self.slabs],
            sigma_a=[list(s.sigma_a_at(wl)) for s in self.slabs], sigma_s=[s.sigma_s for s in self.slabs],
            phase_kind=[s.phase.core_kind for s in self.slabs],
            phase_param=[s.phase.core_parameter for s in self.slabs], options=options)

    def naive(self, wavelengths) -> Any:
        """The core estimator without next-event connections (for benchmarks only)."""
        return self._build(np.asarray(wavelengths, dtype=np.float64), nee=False)

    # -- estimator extras -------------------------------------------------------------
    @renamed_keywords(thickness="thickness_nm")
    def estimate(self, wi, wo, wavelengths=None, samples: int | None = None,
                 seed: int | None = None, lobes: Lobe | int = Lobe.ALL, thickness_nm=None,
                 scattered_only: bool = False, error_walks: int | None = None) -> Estimate:
        """eval with an explicit effort and seed: value, standard error and the count of
        non-finite walks. For colour output the error is the bound sum_l |W_cl| sigma_l
        (channels are correlated: the same walks serve all). ``scattered_only`` leaves out
        the top interface's own reflection (what a table stores, see `exact_part`).

        ``error_walks`` extra walks, from a seed stream independent of the value's, serve
        the standard error alone: it pools their per-walk spread with the value's walks'
        (heavy-tailed walks read a small spread exactly when their mean is small, so the
        value's own spread under-covers; docs/coverage.md). Default None:
        ``ERROR_WALKS_PER_SAMPLE`` (4) x ``samples``, so the call costs 5x the walks; 0: the
        value's own spread (the error before this option). The value never changes with it.
        ``nonfinite`` and ``capped`` count the extra walks too."""
        a, b = check.direction_pair(wi, wo)
        wl, to_rgb = self._channels(wavelengths)
        t = check.per_row("thickness_nm", thickness_nm, len(a), 0.0, check.MAX_FILM_THICKNESS_NM)
        n = self.samples if samples is None else _positive_int("samples", samples)
        s = self.seed if seed is None else check.seed(seed)
        extra = (min(ERROR_WALKS_PER_SAMPLE * n, MAX_WALKS) if error_walks is None
                 else check.integer("error_walks", error_walks, 0, MAX_WALKS))
        core = self._core(wl)
        if scattered_only:
            core = core.scattered_part()
        value, err, bad, capped = core.estimate(a, b, check.lobe_mask(lobes), t, n, s, extra)
        if capped:
            warnings.warn(f"{capped} walks reached max_depth = {self.max_depth} and were cut "
                          "(the estimate is biased low): raise max_depth", RuntimeWarning, stacklevel=2)
        if to_rgb is not None:
            value, err = value @ to_rgb.T, err @ np.abs(to_rgb).T
        return Estimate(value, err, int(bad), int(capped))

    @renamed_keywords(thickness="thickness_nm")
    def eval_with_error(self, wi, wo, wavelengths=None, samples: int | None = None,
                        seed: int | None = None, lobes: Lobe | int = Lobe.ALL, thickness_nm=None,
                        error_walks: int | None = None):
        """(value, standard error), each (N, C): `estimate` without the non-finite count
        (``error_walks`` as there: by default 4x ``samples`` extra walks for the error;
        pass 0 where the error is not used)."""
        e = self.estimate(wi, wo, wavelengths, samples, seed, lobes, thickness_nm, error_walks=error_walks)
        return e.value, e.stderr

    @property
    def capped_walks(self) -> int:
        """Walks of ``eval``, ``sample`` and ``pdf`` (all wavelength sets so far) that
        max_depth cut: truncated, so biased low; 0 for a sound model (``estimate`` reports
        its own)."""
        return sum(int(core.capped_walks) for core in self._cores.values())

    @property
    def exact_part(self) -> BSDF:
        """The part of the model known in closed form: the top interface, whose own
        reflection eval adds exactly (a table stores the rest and adds this back)."""
        return self.interfaces[0]

    @property
    def film_thickness_nm(self) -> float:
        """Total thickness (nm) of the top interface's film, or -1 without a film (what a
        per-query film thickness replaces)."""
        film = getattr(self.interfaces[0], "film", ()) or ()
        return float(sum(layer.thickness_nm for layer in film)) if film else -1.0

    @renamed_keywords(thickness="thickness_nm")
    def delta_reflectance(self, wi, wavelengths=None, thickness_nm=None) -> np.ndarray:
        """Reflectance of the top interface's delta lobe toward the mirror direction, (N, C)."""
        a = check.directions("wi", wi)
        wl, to_rgb = self._channels(wavelengths)
        t = check.per_row("thickness_nm", thickness_nm, len(a), 0.0, check.MAX_FILM_THICKNESS_NM)
        r = self._core(wl).delta_reflectance(a, t)
        return r @ to_rgb.T if to_rgb is not None else r

    # -- serialisation ----------------------------------------------------------------
    def _params(self) -> dict[str, Any]:
        return {"interfaces": [m.to_dict() for m in self.interfaces],
                "slabs": [s.to_dict() for s in self.slabs], "base": self.base.to_dict(),
                "samples": self.samples, "seed": self.seed, "max_depth": self.max_depth,
                **({} if self.pdf_samples == PDF_SAMPLES else {"pdf_samples": self.pdf_samples}),
                **({} if self.estimator == ESTIMATOR else {"estimator": self.estimator})}


def _positive_int(name: str, value) -> int:
    # walks and depths are the core's int32; 2^24 walks per query is already minutes of work
    return check.count(name, value, MAX_WALKS if name == "samples" else MAX_DEPTH)

