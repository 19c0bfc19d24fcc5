r"""Adding-doubling for a ``bsdflab.Layered`` stack: the deterministic twin of its
Position-Free Monte Carlo estimator (docs/solvers.md; core/include/bsdflab/adding_doubling.h).

Method (Jakob et al. 2014, "A comprehensive framework for rendering layered materials";
van de Hulst 1980): radiance in each medium is a cosine series in the propagation-azimuth
difference, sampled at Gauss-Legendre nodes in mu = |cos theta| on panels cut at the
critical cosines. The interfaces' operators are cosine transforms over azimuth of the
core's own BSDF values (rough dielectrics and conductors, GGX or Beckmann, film-coated or
not, ``multiscatter`` as the models define it; Lambertian bases) and of the delta
weights of smooth ones, so the solver and PFMC share one definition of every interface.
Slabs (isotropic or Henyey-Greenstein, spectral sigma_a, grey sigma_s) are doubled from
a single-scattering layer with a Richardson-corrected start; the adding equations join
everything from the base up, one independent task per (wavelength, Fourier order) on all
cores with the GIL released.

What it computes: f |cos theta_o| exactly as ``Layered.eval`` (without delta lobes):
reflection from above for every stack, a rough top's own reflection evaluated directly
and the light that entered the stack solved; for a transmissive stack with a smooth top
and a smooth dielectric base (``Solution.two_sided``) also transmission both ways and
reflection from below (the stack's four operators by the adding equations); the same
for a smooth top over a rough dielectric base (``Solution.every_pair``), the base's
transmission lobes product-integrated at the exit and the entry and its own reflection
from below evaluated directly; and for a rough top over a smooth or rough dielectric base
(``every_pair``), the top's lobes product-integrated the same way above (over a rough base
the beam between the two lobes on their common fine nodes). A rough base under a smooth
interior interface between unequal indices: pairs with wi.z < 0 or wo.z < 0 raise
ValueError naming it (an opaque stack's are zero, its value). Every other stack
``Layered`` accepts is solved or refused with a ValueError naming its code in ``GAPS``
(docs/solvers.md, "Solved and refused").

Validated range (tests/solvers, docs/solvers.md): alpha in [1e-3, 1] for rough
interfaces and bases (ValueError outside); Henyey-Greenstein |g| <= 0.95 (ValueError
beyond), with at least ``nodes_for_g(g)`` nodes per panel (raised automatically, with a
warning naming the new count). Units: wavelengths in nm, slab thickness in µm, sigma in 1/µm.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF
from bsdflab.layered import Layered
from bsdflab.lobes import Lobe
from bsdflab.util import args as check

ALPHA_RANGE = (1e-3, 1.0)
MAX_G = 0.95
DEFAULT_NODES = 16
DEFAULT_THIN_DEPTH = 2.0 ** -16
DEFAULT_ORDER_TOLERANCE = 1e-6
DEFAULT_FINE_STEP = 0.25
PHASES = ("isotropic", "hg")
# Bases (by their registry tag, ``type_name``: bsdflab.measured lies above this layer) the
# solver takes its operators from (cosine transforms of their eval, or their delta
# weights); spectral ``measured`` files are isotropic by the reader's check.
BASES = ("diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric", "measured")
RGB_BASES = ("merl",)  # and RGB measured files
PROBE_NM = 550.0  # solves_every_pair's one wavelength (the rule depends on no wavelength)
# A rough base's exits: its transmission lobe is ~contrast x alpha wide (contrast = |n1 - n2|
# / max); the core's fine sub-panels and azimuth samples follow it down to this contrast and
# no further (core/src/adding_doubling_exits.cpp, the clamp). Below it the bound grows (18 %
# at 1.45 / 1.5, 27 % at 1.47 / 1.5, 4 x 4 x 5 table at a 1 % target) and values turn
# negative (1.49 / 1.5): a table leaves such a stack to PFMC (bsdflab/tables/deterministic.py).
MIN_EXIT_CONTRAST = 1.0 / 16.0

# Every stack ``bsdflab.Layered`` accepts is either solved or refused with one of these
# reasons, by code (docs/solvers.md, "Solved and refused"; tests/solvers/
# test_solver_refusals.py enumerates the combinations). The stack-wide ones are raised by
# ``check_model`` (so by ``solve``); the exit ones by ``Solution.eval`` for the pairs
# they concern (reflection from above stays solved).
GAPS = {
    "not-layered": "the solver solves bsdflab.Layered stacks",
    "alpha-range": f"outside the solver's validated roughness range [{ALPHA_RANGE[0]}, {ALPHA_RANGE[1]}]",
    "phase-kind": "only isotropic and Henyey-Greenstein slabs have Fourier coefficients here "
                  "(von Mises-Fisher is not implemented)",
    "hg-range": f"beyond the validated |g| <= {MAX_G} (the nodes needed grow as 6 / (1 - |g|))",
    "smooth-interior-rough-top": "a smooth interior interface between unequal indices is solved under a smooth "
                                 "top only (its nodes are one set in n sin(theta) shared by every slab; a rough "
                                 "top's product integration is built on the first slab's own panels: not "
                                 "joined, PFMC remains the path)",
    "rgb-base": "the base answers in RGB only and the solver works per wavelength (MERL files, RGB .bsdf "
                "files; PFMC remains the path)",
    "base-kind": "the solver takes its operators from Diffuse, Conductor, RoughConductor, Dielectric, "
                 "RoughDielectric and spectral Measured bases only",
    "rough-exit": "transmission and reflection from below through a rough base under a smooth interior "
                  "interface between unequal indices would need the base's product integration on that "
                  "solve's nodes in n sin(theta) (not implemented): for pairs with wi.z < 0 or wo.z < 0 use "
                  "the model's own eval (PFMC)",
}


def refusal(code: str, detail: str) -> ValueError:
    """The ValueError of gap ``code``: what in the model, then why (``GAPS``)."""
    return ValueError(f"adding-doubling refuses [{code}]: {detail}: {GAPS[code]}")


def nodes_for_g(g: float) -> int:
    """Nodes per panel that resolve a Henyey-Greenstein lobe of asymmetry g (its width in
    cosine is ~ 1 - |g|): 6 / (1 - |g|), at least 8."""
    return max(8, int(np.ceil(6.0 / (1.0 - abs(g)))))


@dataclass(frozen=True)
class Settings:
    """Truncations of the solve: Gauss-Legendre nodes per panel, Fourier orders (None:
    from the phase functions and the roughness of the boundaries below the top), the
    optical depth of the doubling's start, the order tolerance, the half-period azimuth
    samples of the interfaces' cosine transforms (None: automatic), and for a rough top
    the spectral stride of what lies below it (solved at every stride-th wavelength,
    cubic in wavelength between) and the fine sub-panel width (``fine_step`` x alpha
    radians) of its product integration."""

    nodes: int = DEFAULT_NODES
    orders: int | None = None
    thin_depth: float = DEFAULT_THIN_DEPTH
    order_tolerance: float = DEFAULT_ORDER_TOLERANCE
    film_lookup: bool = False
    azimuth_samples: int | None = None
    spectral_stride: int = 1
    fine_step: float = DEFAULT_FINE_STEP

    def coarser(self, orders_used: int, azimuth_used: int | None = None) -> Settings:
        """Every truncation coarser: half the nodes, 2/3 of the orders, a 16 x thicker
        start, half the azimuth samples, twice the spectral stride and the fine step: the
        a-posteriori check (node convergence is geometric but not monotone for a rough
        top, so the coarse solve halves the nodes)."""
        return replace(self, nodes=max(4, self.nodes // 2), orders=max(1, (2 * orders_used) // 3),
                       thin_depth=16.0 * self.thin_depth,
                       azimuth_samples=max(16, azimuth_used // 2) if azimuth_used else None,
                       spectral_stride=2 * self.spectral_stride if self.spectral_stride > 1 else 1,
                       fine_step=2.0 * self.fine_step)

    def to_dict(self) -> dict:
        return {"nodes": self.nodes, "orders": self.orders, "thin_depth": self.thin_depth,
                "order_tolerance": self.order_tolerance, "film_lookup": self.film_lookup,
                "azimuth_samples": self.azimuth_samples, "spectral_stride": self.spectral_stride,
                "fine_step": self.fine_step}


class Solution:
    """A solved stack at fixed wavelengths: ``eval`` and ``eval_with_error`` of direction
    pairs (light arrives from wo, leaves toward wi, both unit, +z up)."""

    def __init__(self, model: Layered, wavelengths, settings: Settings):
        self.model = model
        self.settings = settings
        self._wl, self._to_rgb = BSDF._channels(model, wavelengths)
        self._core = _build(model, self._wl, settings)
        self._coarse = None
        self._coarse_fine_step = None
        self._transmits = bool(model.lobes & Lobe.TRANSMISSION)

    def _coarse_core(self):
        if self._coarse is None:
            self._coarse = _build(self.model, self._wl,
                                  self.settings.coarser(self.orders, self.azimuth_samples))
        return self._coarse

    def _fine_step_core(self):
        """A rough base's or top's exits: the same solve with only the fine step doubled.
        A transmission lobe is cut by the half-vector's horizon (a jump in the BSDF), so
        the product integration converges like the sub-panel width, with changing sign:
        the all-coarser solve's change can cancel it (measured: 6.6e-5 against an error of
        2e-4 at a grazing pair), this one's alone does not."""
        if self._coarse_fine_step is None:
            self._coarse_fine_step = _build(self.model, self._wl,
                                            replace(self.settings, fine_step=2.0 * self.settings.fine_step))
        return self._coarse_fine_step

    def with_model(self, model: Layered) -> Solution:
        """The solution of ``model``, which may differ from this one's only in its rough
        top (e.g. another film thickness): what lies below the top is solved once and
        shared (the expensive part: slabs and base per wavelength and order)."""
        mine, theirs = self.model.to_dict(), model.to_dict() if isinstance(model, Layered) else None
        if theirs is None or {**mine, "interfaces": mine["interfaces"][1:]} != {
                **theirs, "interfaces": theirs["interfaces"][1:]} or not hasattr(self.model.interfaces[0], "alpha"):
            raise ValueError("with_model needs a Layered model that differs only in its rough top")
        new = object.__new__(Solution)
        new.model, new.settings, new._wl, new._to_rgb = model, self.settings, self._wl, self._to_rgb
        new._transmits = bool(model.lobes & Lobe.TRANSMISSION)
        top = model.interfaces[0]._core(self._wl)
        new._core = self._core.with_top(top)
        new._coarse = self._coarse_core().with_top(top)
        new._coarse_fine_step = None
        return new

    @property
    def film_lookup_error(self) -> float | None:
        """Largest measured error of the film lookups used (None: none)."""
        err = float(self._core.film_lookup_error)
        return err if err >= 0 else None

    @property
    def orders(self) -> int:
        """Fourier orders used."""
        return int(self._core.orders)

    @property
    def azimuth_samples(self) -> int:
        """Half-period azimuth samples of the cosine transforms used."""
        return int(self._core.azimuth_samples)

    @property
    def two_sided(self) -> bool:
        """Whether every pair is solved: transmission both ways and reflection from below
        (a transmissive stack with a smooth top and a smooth dielectric base)."""
        return bool(self._core.two_sided)

    @property
    def every_pair(self) -> bool:
        """Whether every pair is solved: ``two_sided``, or a transmissive stack with a
        smooth or rough top over a smooth or rough dielectric base (the rough boundaries'
        exits by product integration), except a rough base under a smooth unmatched
        interior interface."""
        return bool(self._core.every_pair)

    def _pairs(self, wi, wo) -> tuple[np.ndarray, np.ndarray]:
        a, b = check.direction_pair(wi, wo)
        if self._transmits and not self.every_pair and np.any((a[:, 2] < 0) | (b[:, 2] < 0)):
            raise refusal("rough-exit", f"this stack transmits through {exit_gap_reason(self.model)}, and "
                                        f"adding-doubling solves transmission and reflection from below "
                                        f"for a smooth or rough top over a smooth or rough dielectric base "
                                        f"only where no smooth unmatched interior interface lies above a "
                                        f"rough base")
        return a, b

    def eval(self, wi, wo, scattered_only: bool = False) -> np.ndarray:
        """f(wi, wo) |cos theta_o|, (N, C), light arriving from wo and leaving toward wi:
        reflection from above; for an ``every_pair`` stack every pair (transmission both
        ways, reflection from below); 0 for the other pairs of an opaque stack (its
        value). Another transmissive stack (a rough base under a smooth unmatched interior
        interface) raises ValueError for pairs with wi.z < 0 or wo.z < 0.
        ``scattered_only`` leaves out the entry boundary's own reflection: a rough top's
        from above (what a table stores; ``Layered.exact_part`` re-adds it), a rough
        base's from below (as ``Layered.estimate(scattered_only=True)``)."""
        a, b = self._pairs(wi, wo)
        out = self._core.eval(a, b, bool(scattered_only))
        return out @ self._to_rgb.T if self._to_rgb is not None else out

    def eval_with_error(self, wi, wo, scattered_only: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(eval, a-posteriori error bound), each (N, C): the bound is the change to a
        solve with every truncation coarser (``Settings.coarser``: half the nodes and
        azimuth samples, 2/3 of the orders, a 16 x thicker doubling start, twice the
        spectral stride and fine step); the truncations converge geometrically, the start
        quadratically, so the error of the finer solve is below that change (tests/solvers
        checks it). Through a rough base or top (``every_pair``, not ``two_sided``) the
        change to a solve with only the fine step doubled is added (``_fine_step_core``). Per pair,
        the largest relative change over the channels applies to every channel (the
        change alone crosses zero where the error does not). Not covered: a rough top's
        sub-panels are clamped to [0.004, 0.05] rad in both solves, so for alpha x
        ``fine_step`` >= 0.05 (alpha >= 0.2 at the default, 0.1 in tables) or <= 0.002 the
        fine step's error is missed (docs/known_limits.md)."""
        a, b = self._pairs(wi, wo)
        fine = self._core.eval(a, b, bool(scattered_only))
        coarse = self._coarse_core().eval(a, b, bool(scattered_only))
        err = np.abs(fine - coarse)
        if self.every_pair and not self.two_sided:  # a rough base's exits (_fine_step_core)
            err += np.abs(fine - self._fine_step_core().eval(a, b, bool(scattered_only)))
        # The change crosses zero where fine and coarse swap order at some wavelength while
        # the error does not: each pair's largest relative change over its channels
        # applies to all of them (never below the change itself).
        mag = np.abs(fine)
        rel = np.max(np.divide(err, mag, out=np.zeros_like(err), where=mag > 0), axis=1, keepdims=True)
        err = np.maximum(err, rel * mag)
        if self._to_rgb is not None:
            return fine @ self._to_rgb.T, err @ np.abs(self._to_rgb).T
        return fine, err


def solve(model: Layered, wavelengths=None, nodes: int = DEFAULT_NODES, orders: int | None = None,
          thin_depth: float = DEFAULT_THIN_DEPTH,
          order_tolerance: float = DEFAULT_ORDER_TOLERANCE, film_lookup: bool = False,
          azimuth_samples: int | None = None, spectral_stride: int = 1,
          fine_step: float = DEFAULT_FINE_STEP) -> Solution:
    """Adding-doubling solution of a ``Layered`` model (module docstring).

    Parameters
    ----------
    model : Layered
        Interfaces smooth or rough (alpha in [1e-3, 1]); slabs isotropic or
        Henyey-Greenstein with |g| <= 0.95; base any BSDF (alpha in [1e-3, 1] if rough).
    wavelengths : array_like or None
        Vacuum wavelengths in nm (one column each), or None for linear sRGB through the
        default 5 nm grid.
    nodes : int in [4, 256]
        Gauss-Legendre nodes per cosine panel (raised to ``nodes_for_g`` with a warning).
    orders : int in [1, 4096] or None
        Fourier orders in azimuth (None: automatic).
    thin_depth : float in (0, 1]
        Largest optical depth of the doubling's single-scattering start.
    order_tolerance : float in (0, 0.1]
        Automatic orders: Henyey-Greenstein coefficients below this are dropped.
    film_lookup : bool
        Read the interfaces' films from their cosine lookups (core film_lookup.h, measured
        error <= 1e-7 absolute, as PFMC tabulation does) instead of the Airy sum: faster
        for 81 wavelengths. ``Solution.film_lookup_error`` reports the measured error.
    azimuth_samples : int in [8, 16384] or None
        Half-period samples of the interfaces' cosine transforms over azimuth (None:
        automatic, at least 4 x orders and orders + 10 / alpha).
    spectral_stride : int in [1, 64]
        Rough top: solve what lies below it at every stride-th wavelength (and the last)
        and interpolate the rest (cubic Lagrange in wavelength); for many wavelengths and a
        stack below that is smooth in wavelength (tables use 4 for 81 wavelengths).
    fine_step : float in [0.05, 2]
        Rough top: fine sub-panels of ``fine_step`` x alpha radians (clamped to [0.004,
        0.05]) for the product integration of its lobes.
    """
    check_model(model)
    nodes = check.integer("nodes", nodes, 4, 256)
    if orders is not None:
        orders = check.integer("orders", orders, 1, 4096)
    thin_depth = check.real_scalar("thin_depth", thin_depth, 0.0, 1.0, lo_open=True)
    order_tolerance = check.real_scalar("order_tolerance", order_tolerance, 0.0, 0.1, lo_open=True)
    for i, s in enumerate(model.slabs):
        g = s.phase.g if s.phase.type == "hg" else 0.0
        if s.sigma_s > 0 and nodes < nodes_for_g(g):
            warnings.warn(f"adding-doubling: nodes raised from {nodes} to {nodes_for_g(g)} to "
                          f"resolve slabs[{i}]'s Henyey-Greenstein g = {g}", stacklevel=2)
            nodes = nodes_for_g(g)
    if not isinstance(film_lookup, (bool, np.bool_)):
        raise ValueError(f"film_lookup must be True or False, got {film_lookup!r}")
    if azimuth_samples is not None:
        azimuth_samples = check.integer("azimuth_samples", azimuth_samples, 8, 16384)
    spectral_stride = check.integer("spectral_stride", spectral_stride, 1, 64)
    fine_step = check.real_scalar("fine_step", fine_step, 0.05, 2.0)
    return Solution(model, wavelengths, Settings(nodes, orders, thin_depth, order_tolerance, bool(film_lookup),
                                                 azimuth_samples, spectral_stride, fine_step))


def check_model(model) -> None:
    """ValueError naming why ``model`` is outside what this solver solves (``model_gap``;
    the exit gap of a transmissive stack is ``Solution.eval``'s, per pair)."""
    gap = model_gap(model)
    if gap is not None:
        raise refusal(*gap)


def model_gap(model) -> tuple[str, str] | None:
    """(code, detail) of the first stack-wide gap of ``model`` (``GAPS``), or None."""
    if not isinstance(model, Layered):
        return "not-layered", f"model must be a Layered stack, got {type(model).__name__}"
    for name, part in [(f"interfaces[{i}]", m) for i, m in enumerate(model.interfaces)] + [("base", model.base)]:
        alpha = getattr(part, "alpha", None)
        if alpha is not None and not ALPHA_RANGE[0] <= alpha <= ALPHA_RANGE[1]:
            return "alpha-range", f"{name}.alpha must be in [{ALPHA_RANGE[0]}, {ALPHA_RANGE[1]}], got {alpha}"
    for i, s in enumerate(model.slabs):
        if s.phase.type not in PHASES:
            return "phase-kind", f"slabs[{i}].phase must be one of {', '.join(PHASES)}, got {s.phase.type!r}"
        g = s.phase.g if s.phase.type == "hg" else 0.0
        if abs(g) > MAX_G:
            return "hg-range", f"slabs[{i}].phase.g must be in [-{MAX_G}, {MAX_G}], got {g}"
    media = media_indices(model)
    rough_top = bool(model.interfaces[0].lobes & Lobe.SMOOTH)
    for j, part in enumerate(model.interfaces[1:], start=1):  # the core's rule (adding_doubling.cpp)
        if rough_top and not part.lobes & Lobe.SMOOTH and abs(media[j] - media[j + 1]) > 1e-9 * media[j]:
            return "smooth-interior-rough-top", (f"interfaces[{j}] is a smooth interior interface between "
                                                 f"different indices ({media[j]} above, {media[j + 1]} below) "
                                                 f"under a rough top")
    base = model.base
    kind = getattr(base, "type_name", None)
    if kind in RGB_BASES or (kind == "measured" and not base.spectral):
        return "rgb-base", f"the base is a {kind!r} model that stores RGB"
    if kind not in BASES:
        return "base-kind", f"the base is a {kind or type(base).__name__!r} model"
    return None


def solves_every_pair(model) -> bool:
    """Whether ``solve(model)`` answers every direction pair (``Solution.every_pair``:
    transmission both ways and reflection from below), asked without a solve: the core
    decides it when it sets the stack up, at one wavelength here, before any operator is
    built (the solve runs at the first eval). False where ``model_gap`` finds a gap. The
    one rule adding-doubling tables follow (bsdflab/tables/deterministic.py)."""
    if model_gap(model) is not None:
        return False
    return Solution(model, [PROBE_NM], Settings()).every_pair


def base_contrast(model: Layered) -> float | None:
    """|n_above - n_below| / max of a transmissive rough base (None: not one)."""
    media = media_indices(model)
    if getattr(model.base, "alpha", None) is None or not media[-1] > 0:
        return None
    return abs(media[-2] - media[-1]) / max(media[-2], media[-1])


def exit_gap_reason(model: Layered) -> str:
    """Why a transmissive stack's pairs below are refused (``[rough-exit]``): its rough base
    under a smooth interior interface between unequal indices (the only such stack)."""
    return "a rough base under a smooth interior interface between unequal indices"


def media_indices(model: Layered) -> list[float]:
    """Real indices of the exterior, every slab, and the medium below (0: opaque base)."""
    media = [float(model.interfaces[0].ext_ior)] + [float(m.int_ior) for m in model.interfaces]
    below = getattr(model.base, "int_ior", None)
    media.append(float(below) if isinstance(below, (int, float)) else 0.0)
    return media


def _build(model: Layered, wl: np.ndarray, s: Settings):
    boundaries = [m._core(wl) for m in (*model.interfaces, model.base)]
    slabs = model.slabs
    return _core.AddingDoubling(
        list(wl), boundaries, media_indices(model), [x.thickness_um for x in slabs],
        [list(x.sigma_a_at(wl)) for x in slabs], [x.sigma_s for x in slabs],
        [x.phase.g if x.phase.type == "hg" else 0.0 for x in slabs], s.nodes, s.orders or 0,
        s.thin_depth, s.order_tolerance, s.azimuth_samples or 0, s.film_lookup, s.spectral_stride, s.fine_step)
