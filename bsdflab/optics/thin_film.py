"""Exact coherent optics of thin films and multilayer stacks.

A film is either a `FilmStack(incident, layers, substrate)` of `FilmLayer(material,
thickness_nm)`s, or the tuple ``(n0, n1, d_nm, n2)`` for one film of index n1 and
thickness d_nm between an incident medium n0 and a substrate n2. Materials are dispersion
models (`bsdflab.optics.dispersion`), dicts of them, or numbers n + i k (k >= 0 absorbing).

Functions
---------
film_amplitudes(film, wavelength_nm, theta=None, *, cos_theta=None, thickness_nm=None,
                reverse=False) -> FilmAmplitudes(r_s, r_p, t_s, t_p)
film_reflectance(film, wavelength_nm, theta=None, *, cos_theta=None,
                 polarisation="unpolarised", thickness_nm=None, reverse=False) -> ndarray
film_transmittance(...)  same arguments as film_reflectance -> ndarray

Arguments
---------
wavelength_nm
    Vacuum wavelengths in nm, in [1, 1e12].
theta or cos_theta (exactly one)
    Angle of incidence in radians in [0, pi/2], or its cosine in [0, 1], measured in the
    medium the light arrives from.
thickness_nm
    Replaces the thickness of a one-layer film (nm, in [0, 1e9]), to sweep d.
reverse
    Light arrives from the substrate side (the stack is traversed bottom-up; theta is
    then measured in the substrate).
polarisation
    "s", "p" or "unpolarised" (the mean of the s and p power fractions).

wavelength_nm, the angle and thickness_nm broadcast against each other; results have
the broadcast shape. Reflectance and transmittance need a non-absorbing medium of
incidence (k = 0); amplitudes do not.

Conventions
-----------
Amplitudes follow `bsdflab.optics.fresnel` (and the `tmm` package): for one film,

    r = (r01 + r12 e^{2i delta}) / (1 + r01 r12 e^{2i delta}),
    delta = 2 pi n1 d cos(theta1) / lambda,

with the reflection phases already in the signs of r01 and r12 (adding a separate pi on
top double-counts it). R = |r|^2; T_s = Re(n_out cos_out) / Re(n_in cos_in) |t_s|^2 and
T_p = Re(n_out conj(cos_out)) / Re(n_in conj(cos_in)) |t_p|^2, so R + T = 1 when every
medium is lossless. Stacks are folded up from the substrate (recursive Airy), which
equals the transfer-matrix method and stays finite for thick absorbing layers.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from bsdflab import _core
from bsdflab.optics.dispersion import Constant, Dispersion, as_dispersion, dispersion_from_dict, wavelengths_nm
from bsdflab.util import args as check
from bsdflab.util.args import real_array
from bsdflab.util.deprecation import renamed_attributes

POLARISATIONS = ("s", "p", "unpolarised")
MIN_COSINE = 1e-60


@dataclass(frozen=True)
class FilmLayer:
    """One film of a stack.

    Parameters
    ----------
    material : Dispersion, dict or number
        Its index: a dispersion model, a model's dict, or a number n + i k (n > 0, k >= 0).
    thickness_nm : float
        Thickness in nm, finite and >= 0 (0 leaves the interface below bare).
    """

    material: Dispersion
    thickness_nm: float

    def __post_init__(self):
        object.__setattr__(self, "material", as_dispersion(self.material, "material"))
        object.__setattr__(self, "thickness_nm",
                           check.film_thickness("thickness_nm", self.thickness_nm))

    def to_dict(self) -> dict[str, Any]:
        return {"material": self.material.to_dict(), "thickness_nm": self.thickness_nm}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> FilmLayer:
        return cls(dispersion_from_dict(d["material"]), d["thickness_nm"])


@dataclass(frozen=True)
class FilmStack:
    """A planar multilayer between two half-spaces.

    Parameters
    ----------
    incident : Dispersion, dict or number
        The half-space light arrives from (for `reverse=False`).
    layers : sequence of FilmLayer
        At least one layer, in the order light from `incident` meets them.
    substrate : Dispersion, dict or number
        The half-space below the last layer.
    """

    incident: Dispersion
    layers: tuple[FilmLayer, ...]
    substrate: Dispersion

    def __post_init__(self):
        object.__setattr__(self, "incident", as_dispersion(self.incident, "incident"))
        object.__setattr__(self, "substrate", as_dispersion(self.substrate, "substrate"))
        layers = tuple(self.layers) if isinstance(self.layers, (list, tuple)) else None
        if not layers:
            raise ValueError("layers must be a non-empty list of FilmLayer (for a bare interface "
                             "use bsdflab.optics.fresnel_reflectance)")
        for i, layer in enumerate(layers):
            if not isinstance(layer, FilmLayer):
                raise ValueError(f"layers[{i}] must be a FilmLayer, got {type(layer).__name__}")
        object.__setattr__(self, "layers", layers)

    def reversed(self) -> FilmStack:
        """The same stack seen from the substrate side."""
        return FilmStack(self.substrate, self.layers[::-1], self.incident)

    def to_dict(self) -> dict[str, Any]:
        return {"incident": self.incident.to_dict(),
                "layers": [layer.to_dict() for layer in self.layers],
                "substrate": self.substrate.to_dict()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> FilmStack:
        return cls(dispersion_from_dict(d["incident"]),
                   [FilmLayer.from_dict(layer) for layer in d["layers"]],
                   dispersion_from_dict(d["substrate"]))


class FilmAmplitudes(NamedTuple):
    """Complex reflection and transmission amplitudes for s and p polarisation."""
    r_s: np.ndarray
    r_p: np.ndarray
    t_s: np.ndarray
    t_p: np.ndarray


class _Problem(NamedTuple):
    """Validated inputs, in the order light meets the media; arrays broadcast to `shape`."""
    indices: list[np.ndarray]
    thicknesses: list[np.ndarray]
    cos0: np.ndarray
    wavelength_nm: np.ndarray
    shape: tuple[int, ...]


_FILM_PARAMETERS = """film : FilmStack or tuple (n0, n1, d_nm, n2)
        The stack, or one film: indices (numbers n + i k, n in [1e-3, 1e3], k in [0, 1e3],
        dispersion models or their dicts) and a thickness d_nm in nm (in [0, 1e9]; may be
        an array).
    wavelength_nm : array_like
        Vacuum wavelengths in nm, in [1, 1e12].
    theta : array_like, optional
        Angle of incidence in radians, in [0, pi/2], in the medium light arrives from.
    cos_theta : array_like, optional
        Its cosine, in [0, 1]. Give exactly one of theta and cos_theta.
    thickness_nm : array_like, optional
        Replaces the thickness of a one-layer film (nm, in [0, 1e9]) to sweep it.
    reverse : bool, optional
        Light arrives from the substrate side (theta then lies in the substrate)."""

_POLARISATION = """polarisation : {"unpolarised", "s", "p"}, optional
        One polarisation, or the mean of the two power fractions (default)."""

_RAISES = """Raises
    ------
    ValueError
        For any input outside the ranges above, or shapes that do not broadcast, naming
        the parameter; nothing reaches the C++ core."""


def _documented(doc):
    """Fill the shared parameter text into a docstring."""
    def apply(fn):
        fn.__doc__ = doc.format(film=_FILM_PARAMETERS, polarisation=_POLARISATION,
                                raises=_RAISES)
        return fn
    return apply


@_documented("""Complex amplitude coefficients of a film or stack.

    Parameters
    ----------
    {film}

    Returns
    -------
    FilmAmplitudes
        (r_s, r_p, t_s, t_p), complex arrays of the broadcast shape of wavelength_nm, the
        angle and thickness_nm. Any medium of incidence is allowed here, with the angle's
        cosine taken as real.

    {raises}
    """)
def film_amplitudes(film, wavelength_nm, theta=None, *, cos_theta=None, thickness_nm=None,
                    reverse: bool = False) -> FilmAmplitudes:
    problem = _problem(film, wavelength_nm, theta, cos_theta, thickness_nm, reverse, power=False)
    return FilmAmplitudes(*_solve(problem)[:4])


@_documented("""Reflected power fraction R = |r|^2, in [0, 1].

    Parameters
    ----------
    {film}
    {polarisation}

    Returns
    -------
    ndarray
        R, of the broadcast shape of wavelength_nm, the angle and thickness_nm. The medium
        light arrives from must be non-absorbing (k = 0).

    {raises}
    """)
def film_reflectance(film, wavelength_nm, theta=None, *, cos_theta=None,
                     polarisation: str = "unpolarised", thickness_nm=None,
                     reverse: bool = False) -> np.ndarray:
    _check_polarisation(polarisation)
    problem = _problem(film, wavelength_nm, theta, cos_theta, thickness_nm, reverse, power=True)
    return _polarised(*_solve_reflectance(problem), polarisation)


@_documented("""Transmitted power fraction T into the exit medium, in [0, 1].

    T_s = Re(n_out cos_out) / Re(n_in cos_in) |t_s|^2 and
    T_p = Re(n_out conj(cos_out)) / Re(n_in conj(cos_in)) |t_p|^2 (tmm's definitions);
    0 under total internal reflection and at grazing incidence.

    Parameters
    ----------
    {film}
    {polarisation}

    Returns
    -------
    ndarray
        T, of the broadcast shape of wavelength_nm, the angle and thickness_nm. The medium
        light arrives from must be non-absorbing (k = 0).

    {raises}
    """)
def film_transmittance(film, wavelength_nm, theta=None, *, cos_theta=None,
                       polarisation: str = "unpolarised", thickness_nm=None,
                       reverse: bool = False) -> np.ndarray:
    _check_polarisation(polarisation)
    problem = _problem(film, wavelength_nm, theta, cos_theta, thickness_nm, reverse, power=True)
    return _polarised(*_solve(problem)[6:], polarisation)


# -- internals ------------------------------------------------------------------------

def _check_polarisation(polarisation):
    if polarisation not in POLARISATIONS:
        raise ValueError(f"polarisation must be one of {', '.join(map(repr, POLARISATIONS))}; "
                         f"got {polarisation!r}")


def _polarised(s, p, polarisation):
    if polarisation == "s":
        return s
    if polarisation == "p":
        return p
    return 0.5 * (s + p)


def _media(film) -> tuple[list[Dispersion], list[Any], list[str]]:
    """(materials from incident to substrate, layer thicknesses, names for messages)."""
    if isinstance(film, FilmStack):
        media = [film.incident, *(layer.material for layer in film.layers), film.substrate]
        thicknesses = [layer.thickness_nm for layer in film.layers]
    elif isinstance(film, tuple) and len(film) == 4:
        n0, n1, d, n2 = film
        media = [as_dispersion(n0, "n0"), as_dispersion(n1, "n1"), as_dispersion(n2, "n2")]
        thicknesses = [check.film_thickness("d_nm", d, array=True)]
    else:
        raise ValueError("film must be a FilmStack or a tuple (n0, n1, d_nm, n2); "
                         f"got {type(film).__name__}")
    names = ["incident", *(f"layers[{i}]" for i in range(len(thicknesses))), "substrate"]
    return media, thicknesses, names


def _cosine(theta, cos_theta) -> np.ndarray:
    if (theta is None) == (cos_theta is None):
        raise ValueError("give exactly one of theta (radians, [0, pi/2]) and cos_theta ([0, 1])")
    if cos_theta is not None:
        c = real_array("cos_theta", cos_theta, 0.0, 1.0)
    else:
        # A tolerance of a few ulps lets np.pi / 2 itself through.
        t = real_array("theta", theta, 0.0, np.pi / 2 + 1e-12)
        c = np.cos(np.minimum(t, np.pi / 2))
    # Below ~1e-77 the core's fourth powers of n cos underflow and index-matched media give
    # 0 / 0; a cosine of 1e-60 differs from such a one by nothing double precision shows.
    return np.where((c > 0) & (c < MIN_COSINE), MIN_COSINE, c)


def _check_index(name, n):
    ok = (np.isfinite(n) & (n.real >= check.MIN_IOR) & (n.real <= check.MAX_IOR)
          & (n.imag >= 0) & (n.imag <= check.MAX_EXTINCTION))
    if np.all(ok):  # one pass when all is well
        return
    if not np.all(np.isfinite(n)):
        raise ValueError(f"{name} index must be finite at every wavelength")
    if np.any(n.real <= 0):
        raise ValueError(f"{name} index must have a real part n > 0; got min {n.real.min():g}")
    if np.any(n.imag < 0):
        raise ValueError(f"{name} index must have k >= 0 (absorbing); got min {n.imag.min():g}")
    raise ValueError(f"{name} index must have n in [{check.MIN_IOR:g}, {check.MAX_IOR:g}] and k <= "
                     f"{check.MAX_EXTINCTION:g} (docs/limits.md); got n {n.real.min():g} to "
                     f"{n.real.max():g}, k up to {n.imag.max():g}")


def _indices(media, names, wl, power, reverse):
    out = []
    for material, name in zip(media, names):
        if isinstance(material, Constant):
            # checked when made; a single value, which the one-film kernel applies to all rows
            out.append(np.array(complex(material.n, material.k)))
            continue
        n = np.asarray(material.index(wl), dtype=np.complex128)
        _check_index(name, n)
        out.append(n)
    arriving = -1 if reverse else 0
    if power and np.any(out[arriving].imag != 0):
        raise ValueError(f"the medium light arrives from ({names[arriving]}) must be "
                         "non-absorbing (k = 0) for reflectance and transmittance")
    return out


def _problem(film, wavelength_nm, theta, cos_theta, thickness_nm, reverse, power) -> _Problem:
    """All the checks, before any C++ runs."""
    media, thicknesses, names = _media(film)
    if thickness_nm is not None:
        if len(thicknesses) != 1:
            raise ValueError(f"thickness_nm overrides a one-layer film; this stack has "
                             f"{len(thicknesses)} layers")
        thicknesses = [check.film_thickness("thickness_nm", thickness_nm, array=True)]
    wl = wavelengths_nm(wavelength_nm)
    cos0 = _cosine(theta, cos_theta)
    indices = _indices(media, names, wl, power, reverse)
    d = [np.asarray(t, dtype=np.float64) for t in thicknesses]
    try:
        shape = np.broadcast_shapes(wl.shape, cos0.shape, *(t.shape for t in d))
    except ValueError:
        raise ValueError(f"wavelength_nm {wl.shape}, the angle {cos0.shape} and the "
                         f"thicknesses {[t.shape for t in d]} do not broadcast") from None
    if reverse:
        indices, d = indices[::-1], d[::-1]
    return _Problem(indices, d, cos0, wl, shape)


def _flat(a, shape, dtype):
    return np.ascontiguousarray(np.broadcast_to(a, shape), dtype=dtype).ravel()


def _one_film_columns(p: _Problem):
    """Arguments of the one-film kernels; single values stay single (applied to all rows)."""
    def column(a, dtype):
        return np.ravel(a).astype(dtype) if np.size(a) == 1 else _flat(a, p.shape, dtype)

    return (*(column(n, np.complex128) for n in p.indices), column(p.thicknesses[0], np.float64),
            column(p.cos0, np.float64), column(p.wavelength_nm, np.float64))


def _solve(p: _Problem) -> list[np.ndarray]:
    """(r_s, r_p, t_s, t_p, R_s, R_p, T_s, T_p), each of shape p.shape."""
    if len(p.thicknesses) == 1:
        return _with_bare_fallback(p, [np.reshape(a, p.shape) for a in _core.thin_film(*_one_film_columns(p))])
    return _with_bare_fallback(p, _solve_stack(p))


def _solve_stack(p: _Problem) -> list[np.ndarray]:
    n_all = np.stack([np.broadcast_to(n, p.shape) for n in p.indices], axis=-1)
    d_all = np.stack([np.broadcast_to(t, p.shape) for t in p.thicknesses], axis=-1)
    out = _core.film_stack(n_all.reshape(-1, len(p.indices)),
                           d_all.reshape(-1, len(p.thicknesses)),
                           _flat(p.cos0, p.shape, np.float64),
                           _flat(p.wavelength_nm, p.shape, np.float64))
    return [np.reshape(a, p.shape) for a in out]


# A layer thinner than this many wavelengths has no phase a double can hold next to 1.
ABSENT_THICKNESS = 1e-300


def _with_bare_fallback(p: _Problem, out: list[np.ndarray]) -> list[np.ndarray]:
    """Where every layer has zero thickness (or one below ABSENT_THICKNESS wavelengths: the
    slow fuzz found 2e-311 nm) the film is absent and the answer is the bare interface's.
    The kernels clear their fractions into one denominator, which cancels to 0 / 0 for such
    a film near grazing incidence; those entries take the bare interface."""
    bad = ~np.all([np.isfinite(a) for a in out], axis=0)
    if not np.any(bad):
        return out
    absent = np.all([np.broadcast_to(np.abs(t) <= ABSENT_THICKNESS * np.asarray(p.wavelength_nm), p.shape)
                     for t in p.thicknesses], axis=0)
    use = bad & absent
    if not np.any(use):
        return out
    bare = _bare_interface(p)
    return [np.where(use, b, a) for a, b in zip(out, bare[4:6] if len(out) == 2 else bare)]


def _bare_interface(p: _Problem) -> list[np.ndarray]:
    """(r_s, r_p, t_s, t_p, R_s, R_p, T_s, T_p) of the interface incident -> substrate."""
    from bsdflab.optics.fresnel import fresnel_amplitudes

    n_in, n_out = (np.broadcast_to(n, p.shape) for n in (p.indices[0], p.indices[-1]))
    c = np.broadcast_to(p.cos0, p.shape)
    a = fresnel_amplitudes(c, n_in, n_out)
    with np.errstate(divide="ignore", invalid="ignore"):
        T_s = np.real(n_out * a.cos_t) / np.real(n_in * c) * np.abs(a.t_s) ** 2
        T_p = np.real(n_out * np.conj(a.cos_t)) / np.real(n_in * np.conj(c)) * np.abs(a.t_p) ** 2
    same = n_in == n_out
    T_s, T_p = (np.where(same, 1.0, np.nan_to_num(t)) for t in (T_s, T_p))
    return [a.r_s, a.r_p, a.t_s, a.t_p, np.abs(a.r_s) ** 2, np.abs(a.r_p) ** 2, T_s, T_p]


def _solve_reflectance(p: _Problem) -> list[np.ndarray]:
    """(R_s, R_p); one film takes the kernel that skips transmission."""
    if len(p.thicknesses) == 1:
        out = [np.reshape(a, p.shape) for a in _core.thin_film_reflectance(*_one_film_columns(p))]
        return _with_bare_fallback(p, out)
    return _solve(p)[4:6]


# `Layer` was this class's name before issue 34 (it also named the adding-doubling
# oracle's operator quadruple); still importable, with a FutureWarning.
__getattr__ = renamed_attributes(__name__, {"Layer": ("FilmLayer", FilmLayer)})
