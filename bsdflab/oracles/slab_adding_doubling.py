r"""Deterministic reference for scattering slabs: adding-doubling with a Fourier
expansion in azimuth and Gauss-Legendre nodes in cos(theta).

What it models
--------------
From top to bottom: an exterior of real index n_ext; a smooth dielectric interface;
one or more homogeneous slabs sharing the real index n_slab (thickness d in µm,
absorption sigma_a(lambda) and grey scattering sigma_s in 1/µm, an isotropic or
Henyey-Greenstein phase function); and either an opaque Lambertian base of albedo
rho(lambda) (rho = 0: black) or a smooth interface to a medium of index n_below
(n_below = n_slab: no boundary at all, the slab ends in an index-matched medium), which
makes the stack transmissive. In bsdflab terms this is ``Layered([Dielectric(n_slab,
n_ext), Dielectric(n_slab, n_slab), ...], slabs, Diffuse(rho) or Dielectric(n_below,
n_slab))``; ``AddingDoublingOracle.from_layered`` builds it from such a model. The
result is independent of bsdflab's C++ core: its own Fresnel formulas, phase function,
and dense linear algebra in numpy.

Method (Jakob et al. 2014, "A Comprehensive Framework for Rendering Layered
Materials"; van de Hulst 1980; Hovenier et al. 2004). Radiance in the slab medium is
expanded in cos(m dphi) of the propagation-azimuth difference (the smooth interfaces
and the Lambertian base keep every order apart) and sampled at Gauss-Legendre nodes in
mu = |cos theta| on panels cut at the critical cosines (``_ad_boundaries``). Each
slab's reflection and transmission operators come from doubling a single-scattering
layer (``_ad_slab``); the adding equations (``_ad_operators.stack``) join slabs and
boundaries with all inter-reflections. The directions a caller asks about enter as
zero-weight nodes, so the operators are exact there (no interpolation in angle).

What eval returns
-----------------
``eval(wi, wo)`` = f(wi, wo) |cos theta_o| in bsdflab's (Mitsuba's) convention: light
arrives from wo and leaves toward wi (radiance transport, the camera's side is wi).
Reflection (both above), transmission (one above, one below, needs a smooth base) and
reflection from below. The delta parts (the top's specular reflection, unscattered
transmission) are not in eval: ``delta_reflectance`` is the top's Fresnel reflectance,
as ``Layered.delta_reflectance``; ``energy`` gives every part of the balance. For
transmission f carries the radiance factor (n_to / n_from)^2 of the media the light
leaves and enters, as bsdflab's dielectric does for camera paths.

Accuracy (measured by ``bsdflab.oracles.ad_convergence`` and the tests)
----------------------------------------------------------------------
Three truncations: ``nodes`` Gauss-Legendre nodes per panel, ``orders`` Fourier orders
(default: chosen per call from the Henyey-Greenstein pole and the query directions,
coefficients below 1e-7 of the largest), and the starting thickness ``thin_depth`` of the
doubling (error O(tau delta / mu^2), the dominant one). With the defaults (24 nodes,
thin_depth 2^-28) the largest relative change to a run with 48 nodes, 64 orders and
2^-30 is 1.2e-7 over optical depths 0.5-5, albedos 0.5-0.99, g in {0, 0.6, -0.3}, outside
cosines 1 ... 0.02, reflection and transmission (docs/oracles.md has the table; the
stated accuracy is <= 1e-5 relative in that range, tested). Closed forms reproduced:
Chandrasekhar's H-function for a semi-infinite isotropic slab, energy conservation
R + T = 1, reciprocity, the thin-slab single-scattering limit, and CoatedDiffuseOracle
when sigma_s = 0. ``eval_with_error`` returns an a-posteriori bound (the change to a
run with 2/3 of the nodes and orders and a 16 x thicker start).

Valid ranges: real indices > 0; thickness >= 0; sigma_s >= 0 (grey), sigma_a >= 0
(spectral); |g| <= 0.7 with the defaults (sharper phase functions need more nodes:
raise them and check with ``eval_with_error``); phase "isotropic" or "hg" ("vmf" is not
supported). Cost: O(L M (N^3 + q N^2) log2(tau / thin_depth)) for L wavelengths, M
orders, N nodes and q distinct query cosines; isotropic slabs need one order.

Units: wavelengths in nm, slab thickness in µm, sigma_a and sigma_s in 1/µm.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from bsdflab.bsdfs.base import BSDF
from bsdflab.layered.slab import Slab
from bsdflab.oracles import _ad_boundaries as bd
from bsdflab.oracles import _ad_operators as op
from bsdflab.oracles._ad_slab import orders_needed, slab_layer
from bsdflab.spectra import Spectrum
from bsdflab.util import args as check

NODES = 24
THIN_DEPTH = 2.0 ** -28
ORDER_TOLERANCE = 1e-7
PHASES = ("isotropic", "hg")


class AddingDoublingOracle:
    """Deterministic BSDF of a smooth dielectric over scattering slabs over a Lambertian
    or black base, or over a smooth interface to a medium below (module docstring).

    Parameters
    ----------
    int_ior : float > 0
        Index n_slab of every slab.
    ext_ior : float > 0
        Exterior index n_ext.
    slabs : list of Slab or dicts (``bsdflab.layered.Slab``), top first, >= 1
        Thickness (µm), sigma_a (1/µm, spectral), sigma_s (1/µm), phase.
    base_albedo : number, RGB triple, dict or Spectrum in [0, 1], optional
        Lambertian base albedo (0: black). Default 0 unless ``base_ior`` is given.
    base_ior : float > 0, optional
        Index of the medium below a smooth bottom interface (transmissive stack);
        exclusive with ``base_albedo``.
    nodes : int >= 4
        Gauss-Legendre nodes per cosine panel.
    orders : int >= 1, optional
        Fourier orders in azimuth (default: from the phase functions and the query
        directions per call, ``_ad_slab.orders_needed``).
    thin_depth : float > 0
        Largest optical depth of the single-scattering start of the doubling.
    """

    type_name = "adding_doubling_oracle"

    def __init__(self, int_ior: float = 1.5, ext_ior: float = 1.0, slabs=None,
                 base_albedo=None, base_ior=None, nodes: int = NODES, orders=None,
                 thin_depth: float = THIN_DEPTH):
        self.int_ior = check.real_scalar("int_ior", int_ior, 0.0, lo_open=True)
        self.ext_ior = check.real_scalar("ext_ior", ext_ior, 0.0, lo_open=True)
        if not isinstance(slabs, (list, tuple)) or not slabs:
            raise ValueError("slabs must be a non-empty list of Slab or dicts (top first)")
        self.slabs = tuple(Slab.coerce(s, i) for i, s in enumerate(slabs))
        for i, s in enumerate(self.slabs):
            if s.phase.type not in PHASES:
                raise ValueError(f"slabs[{i}].phase must be one of {', '.join(PHASES)}, "
                                 f"got {s.phase.type!r}")
        if base_ior is not None and base_albedo is not None:
            raise ValueError("give base_albedo (opaque Lambertian base) or base_ior "
                             "(smooth interface to a medium below), not both")
        self.base_ior = None if base_ior is None else check.real_scalar(
            "base_ior", base_ior, 0.0, lo_open=True)
        self.base_albedo = None if base_ior is not None else Spectrum.coerce(
            0.0 if base_albedo is None else base_albedo, "base_albedo", 0.0, 1.0)
        self.nodes = check.integer("nodes", nodes, 4)
        self.orders = None if orders is None else check.integer("orders", orders, 1)
        self.thin_depth = check.real_scalar("thin_depth", thin_depth, 0.0, lo_open=True)

    @classmethod
    def from_layered(cls, model, **settings) -> AddingDoublingOracle:
        """The oracle of a ``bsdflab.Layered`` made of a smooth film-free Dielectric top,
        index-matched smooth interior interfaces and a Diffuse (one-sided) or smooth
        film-free Dielectric base; ValueError for anything else."""
        from bsdflab.bsdfs.dielectric import Dielectric
        from bsdflab.bsdfs.diffuse import Diffuse
        top, inner = model.interfaces[0], model.interfaces[1:]
        n = getattr(top, "int_ior", None)
        for i, m in enumerate(model.interfaces):
            if not isinstance(m, Dielectric) or m.film:
                raise ValueError(f"interfaces[{i}] must be a smooth Dielectric without film")
        for i, m in enumerate(inner, start=1):
            if m.int_ior != n or m.ext_ior != n:
                raise ValueError(f"interfaces[{i}] must be index-matched to the slab ({n})")
        base = model.base
        if isinstance(base, Diffuse) and not base.two_sided:
            return cls(n, top.ext_ior, list(model.slabs), base_albedo=base.reflectance, **settings)
        if isinstance(base, Dielectric) and not base.film:
            return cls(n, top.ext_ior, list(model.slabs), base_ior=base.int_ior, **settings)
        raise ValueError("base must be a one-sided Diffuse or a smooth Dielectric without film")

    # -- the BSDF ---------------------------------------------------------------------
    def eval(self, wi, wo, wavelengths=None) -> np.ndarray:
        """f(wi, wo) |cos theta_o| without delta parts, shape (N, C).

        Parameters
        ----------
        wi, wo : array_like, (N, 3) or (3,)
            Unit directions pointing away from the surface (+z normal); z < 0 is below.
        wavelengths : array_like or None
            Vacuum wavelengths in nm (one column each), or None for linear sRGB through
            the default 5 nm grid.
        """
        a, b = check.direction_pair(wi, wo)
        wl, to_rgb = self._channels(wavelengths)
        out = self._eval(a, b, wl, self.nodes, 1.0, self.thin_depth)
        return out @ to_rgb.T if to_rgb is not None else out

    def eval_with_error(self, wi, wo, wavelengths=None) -> tuple[np.ndarray, np.ndarray]:
        """(eval, truncation-error bound), each (N, C): the bound is the change to a run
        with 2/3 of the nodes and orders and a 16 x thicker doubling start (the error of
        geometrically converging truncations is far below that change)."""
        a, b = check.direction_pair(wi, wo)
        wl, to_rgb = self._channels(wavelengths)
        fine = self._eval(a, b, wl, self.nodes, 1.0, self.thin_depth)
        coarse = self._eval(a, b, wl, max(4, (2 * self.nodes) // 3), 2.0 / 3.0,
                            16.0 * self.thin_depth)
        err = np.abs(fine - coarse)
        if to_rgb is not None:
            return fine @ to_rgb.T, err @ np.abs(to_rgb).T
        return fine, err

    def delta_reflectance(self, wi, wavelengths=None) -> np.ndarray:
        """Weight of the top's delta reflection (its Fresnel reflectance), (N, C)."""
        w = check.directions("wi", wi)
        wl, to_rgb = self._channels(wavelengths)
        r = np.where(w[:, 2] > 0, bd.fresnel_reflectance(self.ext_ior, self.int_ior, w[:, 2]), 0.0)
        out = np.repeat(r[:, None], len(wl), axis=1)
        return out @ to_rgb.T if to_rgb is not None else out

    def albedo(self, theta_i, wavelengths=None) -> np.ndarray:
        """Hemispherical reflectance of the non-delta part for light from above at polar
        angles theta_i (radians, [0, pi/2)), shape (N, C); see ``energy`` for the rest."""
        parts = self.energy(theta_i, wavelengths)
        return parts["reflection"]

    def energy(self, theta_i, wavelengths=None) -> dict[str, np.ndarray]:
        """Where light from above at polar angles theta_i (N,) goes, each (N, C):
        ``reflection`` and ``transmission`` (non-delta hemispherical integrals of eval),
        ``delta_reflection`` (the top's specular lobe plus unscattered light returned by a
        smooth base), ``delta_transmission`` (unscattered through everything) and
        ``absorbed`` (the rest; 0 for a lossless stack up to truncation)."""
        theta = np.atleast_1d(check.real_array("theta_i", theta_i, 0.0, np.pi / 2, hi_open=True))
        wl, to_rgb = self._channels(wavelengths)
        parts = self._energy(np.cos(theta.ravel()), wl)
        parts["absorbed"] = 1.0 - sum(parts.values())
        if to_rgb is not None:
            parts = {k: v @ to_rgb.T for k, v in parts.items()}
        return parts

    # -- serialisation ----------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        d = {"type": self.type_name, "int_ior": self.int_ior, "ext_ior": self.ext_ior,
             "slabs": [s.to_dict() for s in self.slabs], "nodes": self.nodes,
             "orders": self.orders, "thin_depth": self.thin_depth}
        if self.base_ior is not None:
            d["base_ior"] = self.base_ior
        else:
            d["base_albedo"] = self.base_albedo.to_dict()
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> AddingDoublingOracle:
        if d.get("type", cls.type_name) != cls.type_name:
            raise ValueError(f"expected type {cls.type_name!r}, got {d.get('type')!r}")
        return cls(**{k: v for k, v in d.items() if k != "type"})

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={v!r}" for k, v in self.to_dict().items() if k != "type")
        return f"AddingDoublingOracle({params})"

    # -- internals --------------------------------------------------------------------
    # (wavelengths, RGB weights or None) exactly as every bsdflab BSDF reads `wavelengths`
    _channels = BSDF._channels

    def _breaks(self) -> list[float]:
        cuts = [bd.critical_cosine(self.int_ior, self.ext_ior)]
        if self.base_ior is not None:
            cuts.append(bd.critical_cosine(self.int_ior, self.base_ior))
        return [c for c in cuts if c is not None]

    def _side(self, z) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For directions with z-components `z`: slab cosine, the interface's
        transmittance and the index of the medium they lie in (0 where no light passes)."""
        up = z > 0
        mu = np.zeros(z.shape)
        trans = np.zeros(z.shape)
        n_out = np.where(up, self.ext_ior, self.base_ior or 0.0)
        mu[up] = bd.refracted_cosine(self.ext_ior, self.int_ior, z[up])
        if self.base_ior is not None:
            down = z < 0
            mu[down] = bd.refracted_cosine(self.base_ior, self.int_ior, -z[down])
        ok = mu > 0
        trans[ok] = 1.0 - bd.fresnel_reflectance(self.int_ior, n_out[ok], mu[ok])
        return mu, trans, n_out

    def _optics(self, wl):
        """Per slab (tau, omega) per wavelength, and the base albedo per wavelength."""
        slabs = []
        for s in self.slabs:
            sigma_t = s.sigma_a_at(wl) + s.sigma_s
            omega = np.divide(s.sigma_s, sigma_t, out=np.zeros_like(sigma_t), where=sigma_t > 0)
            slabs.append((sigma_t * s.thickness_um, omega, s.phase.g if s.phase.type == "hg" else 0.0))
        rho = None if self.base_albedo is None else self.base_albedo.at(wl)
        return slabs, rho

    def _stack(self, cos, pairs, weights, wl, orders, thin_depth) -> op.LayerOperators:
        """The whole stack's operators (top boundary, slabs, base) on cos = (nodes,
        output cosines, input cosines) with the requested (output, input) index pairs."""
        mu, out, inp = cos
        g = op.Grid(bd.flux_weights(mu, weights, orders), pairs[0], pairs[1],
                    (len(wl), orders), len(mu), len(out), len(inp))
        slabs, rho = self._optics(wl)
        if self.base_ior is not None:
            layer = bd.smooth_base_layer(cos, self.int_ior, self.base_ior, g)
        else:
            layer = bd.lambertian_base_layer(rho, g)
        for tau, omega, phase_g in reversed(slabs):
            layer = op.stack(slab_layer(cos, g, tau, omega, phase_g, thin_depth), layer, g)
        return op.stack(bd.top_layer(cos, self.int_ior, self.ext_ior, g), layer, g)

    def orders_for(self, cosines) -> int:
        """Fourier orders used for queries at these slab cosines (``orders`` if given)."""
        if self.orders is not None:
            return self.orders
        sine = float(np.sqrt(max(0.0, 1.0 - float(np.min(cosines)) ** 2))) if len(cosines) else 1.0
        return max(orders_needed(s.phase.g if s.phase.type == "hg" else 0.0, ORDER_TOLERANCE, sine)
                   for s in self.slabs)

    def _eval(self, a, b, wl, nodes, order_scale, thin_depth) -> np.ndarray:
        out = np.zeros((len(a), len(wl)))
        mu_v, t_v, n_v = self._side(a[:, 2])       # viewer: light leaves toward wi
        mu_l, t_l, _ = self._side(b[:, 2])         # light arrives from wo
        active = np.flatnonzero((mu_v > 0) & (mu_l > 0))
        if len(active) == 0:
            return out
        grid, weights = bd.nodes(nodes, self._breaks())
        outputs, pr = np.unique(mu_v[active], return_inverse=True)
        inputs, pc = np.unique(mu_l[active], return_inverse=True)
        orders = max(1, int(np.ceil(order_scale * self.orders_for(np.concatenate([outputs, inputs])))))
        layer = self._stack((grid, outputs, inputs), (pr.ravel(), pc.ravel()), weights, wl,
                            orders, thin_depth)
        # cos(m dphi) of the propagation azimuths: incoming -wo, outgoing wi
        dphi = (np.arctan2(a[active, 1], a[active, 0]) - np.arctan2(b[active, 1], b[active, 0])
                - np.pi)
        cosines = np.cos(np.outer(np.arange(orders), dphi))           # (M, pairs)
        up_v, up_l = a[active, 2] > 0, b[active, 2] > 0
        value = np.zeros((len(wl), len(active)))
        for sel_v, sel_l, o in ((True, True, layer.Rt), (True, False, layer.Tu),
                                (False, True, layer.Td), (False, False, layer.Rb)):
            pick = (up_v == sel_v) & (up_l == sel_l)
            if np.any(pick) and o.Kp is not None:
                kp = np.broadcast_to(o.Kp, (len(wl), orders, len(active)))
                value[:, pick] = np.einsum("lmp,mp->lp", kp[..., pick], cosines[:, pick])
        scale = t_v[active] * t_l[active] * (n_v[active] / self.int_ior) ** 2 * np.abs(b[active, 2])
        out[active] = (value * scale).T
        return out

    def _energy(self, c_i, wl) -> dict[str, np.ndarray]:
        mu_l, t_l, _ = self._side(c_i)
        grid, weights = bd.nodes(self.nodes, self._breaks())
        none = np.zeros(0, dtype=int)
        layer = self._stack((grid, np.zeros(0), mu_l), (none, none), weights, wl, 1, self.thin_depth)
        shape = (len(wl), 1, len(c_i))
        t_top = 1.0 - bd.fresnel_reflectance(self.int_ior, self.ext_ior, grid)
        # order 0 of the outgoing field, integrated over the nodes the light leaves through:
        # int T(mu) K mu dmu dphi (the étendue cancels the (n_out / n_s)^2 of radiance)
        flux = 2.0 * np.pi * grid * weights
        parts = {"reflection": _outflux(layer.Rt, flux * t_top, shape) * t_l[:, None]}
        spec = bd.fresnel_reflectance(self.ext_ior, self.int_ior, c_i)
        parts["delta_reflection"] = spec[:, None] + t_l[:, None] ** 2 * _delta(layer.Rt, shape)
        if self.base_ior is None:
            zero = np.zeros((len(c_i), len(wl)))
            parts["transmission"], parts["delta_transmission"] = zero, zero.copy()
            return parts
        t_bot = 1.0 - bd.fresnel_reflectance(self.int_ior, self.base_ior, grid)
        parts["transmission"] = _outflux(layer.Td, flux * t_bot, shape) * t_l[:, None]
        t_bot_q = 1.0 - bd.fresnel_reflectance(self.int_ior, self.base_ior, mu_l)
        parts["delta_transmission"] = (t_l * t_bot_q)[:, None] * _delta(layer.Td, shape)
        return parts


def _outflux(o: op.Operator, flux: np.ndarray, shape) -> np.ndarray:
    """sum_j flux_j K^0[j, input] over the quadrature nodes, shape (inputs, L)."""
    if o.Kc is None:
        return np.zeros((shape[2], shape[0]))
    return np.einsum("j,ljq->ql", flux, np.broadcast_to(o.Kc, shape[:2] + (len(flux), shape[2]))[:, 0])


def _delta(o: op.Operator, shape) -> np.ndarray:
    """Order-0 delta part of o at the input cosines, shape (inputs, L)."""
    if o.Dc is None:
        return np.zeros((shape[2], shape[0]))
    return np.broadcast_to(o.Dc, shape)[:, 0].T


