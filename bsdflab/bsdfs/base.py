"""The Python face of every BSDF: validated, vectorised calls into the C++ core.

Conventions (see docs/ARCHITECTURE.md): local frame with +z the normal, wi and wo both
pointing away from the surface; ``eval`` returns f * |cos theta_o|; ``pdf`` is a
solid-angle density; ``sample`` returns weight = f |cos theta_o| / pdf. Results have one
column per channel: 3 (linear sRGB under D65) when ``wavelengths`` is None, else one per
requested wavelength (nm). RGB results are spectral results on the default grid projected
through colour-matching functions, never three-wavelength shortcuts.
"""
from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from bsdflab import _core
from bsdflab.lobes import Lobe
from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights
from bsdflab.util import args as check
from bsdflab.util.deprecation import renamed_keywords
from bsdflab.util.registry import Registry

# Types defined in this package register as their classes are created; types defined in
# the layers above (layered models, tables) are lazy entries, so ``from_dict`` finds them
# whatever was imported first, without this layer importing upward.
TYPES: Registry[type[BSDF]] = Registry("BSDF type", lazy={
    "layered": "bsdflab.layered.stack",
    "table": "bsdflab.tables.table_bsdf",
    "measured": "bsdflab.measured.measured_bsdf",
    "merl": "bsdflab.measured.merl",
})


@dataclass(frozen=True)
class BSDFSample:
    """The result of ``BSDF.sample`` for N incident directions."""

    wo: np.ndarray      # (N, 3) sampled outgoing directions (zeros where none)
    weight: np.ndarray  # (N, C) f |cos theta_o| / pdf (zeros where none)
    pdf: np.ndarray     # (N,) solid-angle density; for a delta lobe the probability of picking it
    lobe: np.ndarray    # (N,) the Lobe bit that produced each sample, 0 = failed
    eta: np.ndarray     # (N,) relative index crossed, n_t / n_i (1 for reflection)


class BSDF(abc.ABC):
    """Base class. Subclasses set ``type_name`` and implement ``_build`` and ``_params``."""

    type_name: ClassVar[str] = ""

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        # only a class that names its own type registers: a subclass inheriting the name
        # (a test's mutant, a user's wrapper) would otherwise take the type over for everyone
        if cls.__dict__.get("type_name"):
            TYPES.add(cls.type_name, cls)

    def __init__(self) -> None:
        self._cores: dict[tuple[float, ...], Any] = {}

    # -- to be provided by subclasses -------------------------------------------------
    @abc.abstractmethod
    def _build(self, wavelengths: np.ndarray):
        """The C++ object for these wavelengths (nm)."""

    @abc.abstractmethod
    def _params(self) -> dict[str, Any]:
        """Constructor arguments as plain JSON-compatible values."""

    # -- the interface ----------------------------------------------------------------
    @property
    def lobes(self) -> Lobe:
        return Lobe(self._core(DEFAULT_WAVELENGTHS).lobes)

    @renamed_keywords(thickness="thickness_nm")
    def eval(self, wi, wo, wavelengths=None, lobes: Lobe | int = Lobe.ALL,
             thickness_nm=None) -> np.ndarray:
        """f(wi, wo) |cos theta_o|, shape (N, C).

        ``thickness_nm`` (a number or one per row) replaces a thin-film coating's total
        thickness for this call, e.g. a texture's value at each shading point."""
        a, b = check.direction_pair(wi, wo)
        wl, to_rgb = self._channels(wavelengths)
        t = check.per_row("thickness_nm", thickness_nm, len(a), 0.0, check.MAX_FILM_THICKNESS_NM)
        values = self._core(wl).eval(a, b, check.lobe_mask(lobes), t)
        return values @ to_rgb.T if to_rgb is not None else values

    @renamed_keywords(thickness="thickness_nm")
    def pdf(self, wi, wo, lobes: Lobe | int = Lobe.ALL, thickness_nm=None, wavelengths=None) -> np.ndarray:
        """Solid-angle density of ``sample`` returning wo, shape (N,).

        Where the choice between lobes depends on wavelength (thin films), ``sample`` picks
        with the mean over its channels: pass the same ``wavelengths`` here (None = the
        default colour grid, as for ``sample``) to get the matching density."""
        a, b = check.direction_pair(wi, wo)
        t = check.per_row("thickness_nm", thickness_nm, len(a), 0.0, check.MAX_FILM_THICKNESS_NM)
        wl, _ = self._channels(wavelengths)
        return self._core(wl).pdf(a, b, check.lobe_mask(lobes), t)

    @renamed_keywords(thickness="thickness_nm")
    def sample(self, wi, u1=None, u2=None, *, seed: int = 0, wavelengths=None,
               lobes: Lobe | int = Lobe.ALL, thickness_nm=None) -> BSDFSample:
        """Sample wo for each wi. Uniforms u1 (N,) and u2 (N, 2) are drawn from ``seed``
        (numpy PCG64) when not given, so the call is repeatable."""
        w = check.directions("wi", wi)
        n = len(w)
        if u1 is None or u2 is None:
            rng = np.random.default_rng(check.seed(seed))
            r1, r2 = rng.random(n), rng.random((n, 2))
            u1 = r1 if u1 is None else u1
            u2 = r2 if u2 is None else u2
        u1 = check.uniforms("u1", u1, (n,))
        u2 = check.uniforms("u2", u2, (n, 2))
        wl, to_rgb = self._channels(wavelengths)
        t = check.per_row("thickness_nm", thickness_nm, n, 0.0, check.MAX_FILM_THICKNESS_NM)
        wo, weight, pdf, lobe, eta = self._core(wl).sample(w, u1, u2, check.lobe_mask(lobes), t)
        if to_rgb is not None:
            weight = weight @ to_rgb.T
        return BSDFSample(wo=wo, weight=weight, pdf=pdf, lobe=lobe, eta=eta)

    def render_core(self):
        """(C++ object, P) for the renderer: P (3, C) projects the object's channels to
        linear sRGB, or is None when the object already answers in RGB.

        A model whose answer does not depend on wavelength (constant indices, no film) is
        built for one channel with P's row sums: the same RGB, 81 times less work."""
        core, P = self._core(DEFAULT_WAVELENGTHS), srgb_weights(DEFAULT_WAVELENGTHS)
        if _spectrally_flat(core):
            return self._core(np.array([FLAT_PROBE_NM])), P.sum(axis=1, keepdims=True)
        return core, P

    def render_lift(self) -> np.ndarray | None:
        """(81, C) matrix taking ``render_core()``'s channels to the model's own spectrum on
        the default grid, for spectral rendering; None: the renderer's generic lift
        (render/build.py ``spectral_lift``) is exact for this model."""
        return None

    # -- serialisation ----------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """A plain dict: {'type': ..., parameters...}; inverse of ``from_dict``."""
        return {"type": self.type_name, **self._params()}

    def __eq__(self, other: object) -> bool:
        return isinstance(other, BSDF) and self.to_dict() == other.to_dict()

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={v!r}" for k, v in self._params().items())
        return f"{type(self).__name__}({params})"

    # -- internals --------------------------------------------------------------------
    def _channels(self, wavelengths):
        if wavelengths is None:
            return DEFAULT_WAVELENGTHS, srgb_weights(DEFAULT_WAVELENGTHS)
        wl = np.atleast_1d(check.wavelengths_nm("wavelengths", wavelengths)).ravel()
        if len(wl) > MAX_CHANNELS:
            raise ValueError(f"wavelengths must have at most {MAX_CHANNELS} entries, got {len(wl)}")
        return wl, None

    def _core(self, wavelengths: np.ndarray):
        key = tuple(float(x) for x in wavelengths)
        core = self._cores.get(key)
        if core is None:
            if len(self._cores) > 16:  # bounded: callers may sweep many wavelength sets
                self._cores.clear()
            core = self._cores[key] = self._build(np.asarray(wavelengths, dtype=np.float64))
        return core


FLAT_PROBE_NM = 550.0
# Channels of one evaluation: the core carries per-channel scratch per query.
MAX_CHANNELS = 4096


def _spectrally_flat(core) -> bool:
    """True when eval and sample agree across all channels on a fixed set of directions
    from both sides (grazing included). Flatness comes from the parameters, not the
    directions, so a probe decides it; stochastic (layered) models are never flat."""
    if core.channels < 2 or isinstance(core, _core.LayeredBSDF):
        return False
    theta = np.radians([0.0, 20.0, 45.0, 70.0, 85.0, 100.0, 135.0, 170.0])
    wi = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    wo = np.stack([-np.sin(theta[::-1]) * 0.8, 0.6 * np.sin(theta[::-1]), np.cos(theta[::-1])], axis=1)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    a, b = np.repeat(wi, len(wo), axis=0), np.tile(wo, (len(wi), 1))
    values = [core.eval(a, b, int(Lobe.ALL), None)]
    u = np.random.default_rng(0).random((len(a), 3))
    values.append(core.sample(a, u[:, 0], u[:, 1:], int(Lobe.ALL), None)[1])
    return all(np.ptp(v, axis=1).max() <= 1e-12 * max(1.0, np.abs(v).max()) for v in values)


def from_dict(d: dict[str, Any]) -> BSDF:
    """Rebuild a BSDF from ``to_dict`` output (also the HTTP and table-file form)."""
    if not isinstance(d, dict) or "type" not in d:
        raise ValueError("a BSDF dict needs a 'type' key; known types: " + ", ".join(TYPES.names()))
    check.nesting("the BSDF dict", d)
    kind = d["type"]
    cls = TYPES.get(kind)
    if cls is None:
        raise ValueError(f"unknown BSDF type {check.brief(kind)}; known types: {', '.join(TYPES.names())}")
    params = {k: v for k, v in d.items() if k != "type"}
    if not all(isinstance(k, str) for k in params):
        raise ValueError(f"bad parameters for BSDF type {kind!r}: parameter names must be strings")
    try:
        return cls(**params)
    except RecursionError:
        raise ValueError(f"bad parameters for BSDF type {kind!r}: nested too deeply") from None
    except (TypeError, OverflowError, KeyError, AttributeError) as e:
        raise ValueError(f"bad parameters for BSDF type {kind!r}: {check.one_line(e)}") from None
