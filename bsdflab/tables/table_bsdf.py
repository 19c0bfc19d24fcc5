"""`TableBSDF`: a BSDF read from a table, with the same eval / pdf / sample interface.

Lookup is multilinear over (film thickness, theta_i, theta_o, phi) in the C++ core; for
layered tables the top interface's reflection (glossy and delta) is added back exactly
from the model stored in the table, and in a two-sided table (four lobes, a transmissive
model) the base's reflection of light from below likewise. A layered model's delta lobes (its
unscattered reflection and transmission, from either side: bsdflab/tables/delta.py) are
added at lookup from the model too. Sampling and pdf are described in
core/include/bsdflab/table_bsdf.h.
"""
from __future__ import annotations

import os
import warnings
from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF, from_dict
from bsdflab.bsdfs.interface_term import make_term
from bsdflab.bsdfs.rough import RoughDielectric
from bsdflab.lobes import Lobe
from bsdflab.spectra import DEFAULT_WAVELENGTHS, srgb_weights
from bsdflab.tables.channels import LUMINANCE_RGB, channel_wavelengths
from bsdflab.tables.data import TableData
from bsdflab.tables.delta import delta_stack
from bsdflab.tables.file_format import read_table
from bsdflab.tables.film_axis import old_film_axis


class TableBSDF(BSDF):
    """A tabulated BSDF.

    Parameters
    ----------
    table : TableData, str or path
        The table, or the path of a table file (read and verified).
    film_lookup : bool, optional
        RGB tables only: evaluate the top interface's exact part through an RGB lookup of
        its Fresnel term over (cos theta, film thickness) (fast; interpolation error below
        FILM_LOOKUP_MAX_ERROR) instead of spectrally at every evaluation. Default
        ``FILM_LOOKUP`` (True).
    """

    type_name = "table"

    def __init__(self, table=None, path: str | None = None, film_lookup: bool | None = None):
        super().__init__()
        self.film_lookup = FILM_LOOKUP if film_lookup is None else bool(film_lookup)
        if table is None and path is None:
            raise ValueError("give a table (TableData) or the path of a table file")
        if not isinstance(table, TableData):
            source = table if table is not None else path
            if not isinstance(source, (str, os.PathLike)):
                raise ValueError(f"table must be a TableData or the path of a table file, "
                                 f"got {type(source).__name__}")
            path = os.fspath(source)
            table = read_table(path)
        table.check()
        if (reason := old_film_axis(table)) is not None:
            warnings.warn(reason, RuntimeWarning, stacklevel=2)
        self.table = table
        self.path = path
        self._wavelengths = channel_wavelengths(table.channels)

    @property
    def lobes(self):
        return Lobe(self._core(self._channels(None)[0]).lobes)

    # The table fixes the channels: RGB tables answer in RGB, spectral ones at their own
    # wavelengths; asking for others is an error rather than a silent resampling.
    def _channels(self, wavelengths):
        own = self._wavelengths
        if wavelengths is None:
            return (np.arange(len(self.table.channels), dtype=float) if own is None else own), None
        wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
        if own is None or wl.shape != own.shape or not np.allclose(wl, own):
            raise ValueError(f"this table stores channels {self.table.channels}; "
                             f"wavelengths must be None or exactly those")
        return own, None

    def render_core(self):
        """RGB tables answer in RGB; a spectral table on the default grid's 81 bins answers in
        those bins (projected to RGB by the sensor weights, used as is by spectral renders)."""
        own = self._wavelengths
        if own is None:
            return self._core(self._channels(None)[0]), None
        if own.shape != DEFAULT_WAVELENGTHS.shape or not np.allclose(own, DEFAULT_WAVELENGTHS):
            raise ValueError(f"the renderer needs an RGB table or one on the default {len(DEFAULT_WAVELENGTHS)} "
                             f"wavelengths ({DEFAULT_WAVELENGTHS[0]:g}-{DEFAULT_WAVELENGTHS[-1]:g} nm); this one "
                             f"stores {len(own)} wavelengths")
        return self._core(own), srgb_weights(DEFAULT_WAVELENGTHS)

    @property
    def film_thickness_nm(self) -> float:
        """The film thickness (nm) lookups default to, or -1 without a film."""
        return default_film_thickness(self.table.model)

    def _build(self, channel_ids: np.ndarray):
        t = self.table
        g = t.grid
        direct, below, P = None, None, []
        delta, delta_P = None, []
        if t.split_direct:
            # The stack's delta lobes (unscattered reflection and transmission), summed per
            # wavelength before any projection: the series is not linear in the Fresnel terms.
            wl = DEFAULT_WAVELENGTHS if self._wavelengths is None else self._wavelengths
            W = srgb_weights(wl) if self._wavelengths is None else np.eye(len(wl))
            delta, delta_P = delta_stack(t.model, wl, W)
            model = from_dict(t.model)
            top = model.exact_part
            # A two-sided table leaves out the base's own reflection of light from below
            # (the walks' entry boundary there): it is added back exactly, with its own film.
            base = model.base if t.two_sided else None
            if self._wavelengths is None and not self.film_lookup:
                direct = top._core(DEFAULT_WAVELENGTHS)
                below = base._core(DEFAULT_WAVELENGTHS) if base is not None else None
                P = srgb_weights(DEFAULT_WAVELENGTHS).ravel()
            elif self._wavelengths is None or (self.film_lookup and _default_grid(self._wavelengths)):
                # The film's R and T looked up (RGB, or the 81 bins for a spectral render).
                thickness = [x for x in g.thickness_nm if x >= 0]
                spectral = self._wavelengths is not None
                direct = lookup_interface(top, (min(thickness), max(thickness)) if thickness else None,
                                          default_film_thickness(t.model), spectral=spectral)
                below = (lookup_interface(base, None, film_thickness_of(base), spectral=spectral)
                         if base is not None else None)
                P = np.eye(3 if self._wavelengths is None else len(self._wavelengths)).ravel()
            else:
                direct = top._core(self._wavelengths)
                below = base._core(self._wavelengths) if base is not None else None
                P = np.eye(len(self._wavelengths)).ravel()
        lum = LUMINANCE_RGB if self._wavelengths is None else np.full(len(t.channels), 1 / len(t.channels))
        return _core.TabulatedBSDF(list(channel_ids), len(t.lobes), g.n_theta_i, g.n_theta_o, g.n_phi,
                                   list(g.thickness_nm), t.values.ravel().tolist(), list(lum), direct,
                                   list(P), default_film_thickness(t.model), transmission_eta(t.model),
                                   direct_below=below, delta=delta, delta_P=delta_P)

    def _params(self) -> dict[str, Any]:
        if self.path is None:
            raise ValueError("an in-memory table has no dict form: write it to a file first")
        return {"path": self.path}


def default_film_thickness(model: dict) -> float:
    """Total film thickness (nm) of the model's coating -- the top interface's for a layered
    model, the model's own for a coated interface -- or -1 without a film. The model is
    asked (`film_thickness_of`); a dict that is no valid model has no film."""
    try:
        bsdf = from_dict(model)
    except (ValueError, TypeError):
        return -1.0
    return film_thickness_of(bsdf)


def film_thickness_of(bsdf: BSDF) -> float:
    """A model's film thickness (nm): its own answer (`film_thickness_nm`, e.g. a layered
    model's top film) or the total of its own `film` layers; -1 without a film."""
    own = getattr(bsdf, "film_thickness_nm", None)
    if own is not None:
        return float(own)
    film = getattr(bsdf, "film", None) or ()
    return float(sum(layer.thickness_nm for layer in film)) if film else -1.0


# The RGB lookup of the top interface's Fresnel term (see core/include/bsdflab/projected_term.h):
# nodes uniform in cos theta_i and in film thickness. Its interpolation error, measured
# against the exact spectral film at random off-grid points (tests/test_film_lookup.py),
# is below FILM_LOOKUP_MAX_ERROR in every RGB channel of R and T.
FILM_LOOKUP = True
FILM_LOOKUP_COS_NODES = 257
FILM_LOOKUP_STEP_NM = 1.0
FILM_LOOKUP_MAX_ERROR = 2e-4  # measured: 8.5e-5 at 2000 random points of the snake film


def _default_grid(wavelengths) -> bool:
    return wavelengths.shape == DEFAULT_WAVELENGTHS.shape and np.allclose(wavelengths, DEFAULT_WAVELENGTHS)


def lookup_interface(top: BSDF, thickness_range, default_thickness: float, spectral: bool = False):
    """The core of interface ``top`` answering through a lookup of its spectral Fresnel term:
    projected by the colour weights (linear sRGB), or, ``spectral``, kept on the default
    grid's 81 bins (identity projection: the same bilinear lookup per bin, measured max
    error 8.6e-5 at 2000 random off-grid points of the snake film, within
    FILM_LOOKUP_MAX_ERROR; 20 MB for the snake's thickness range). ``thickness_range`` (nm)
    is the (lo, hi) film-thickness range to tabulate, None for the model's own film only."""
    wl = DEFAULT_WAVELENGTHS
    exact = make_term(wl, top.ext_ior, top.film, int_ior=top.int_ior)
    lo, hi = thickness_range if (thickness_range and top.film) else (-1.0, -1.0)
    n_thickness = max(2, int(np.ceil((hi - lo) / FILM_LOOKUP_STEP_NM)) + 1) if hi > lo else 1
    P, K = (np.eye(len(wl)), len(wl)) if spectral else (srgb_weights(wl), 3)
    term = _core.ProjectedFresnelTerm(exact, list(P.ravel()), K, float(lo), float(hi),
                                      float(default_thickness), FILM_LOOKUP_COS_NODES, n_thickness)
    ids = list(map(float, wl)) if spectral else [0.0, 1.0, 2.0]
    if isinstance(top, RoughDielectric):  # its own distribution and energy compensation
        return top._interface(ids, term, False)
    return _core.SmoothInterface(ids, term, False)


def transmission_eta(model: dict) -> float:
    """n_t / n_i across a layered model (the product of its boundaries' int/ext ratios),
    1 when the model does not say."""
    try:
        eta = 1.0
        for b in [*model["interfaces"], model["base"]]:
            if "int_ior" in b and "ext_ior" in b:
                eta *= float(b["int_ior"]) / float(b["ext_ior"])
        return eta
    except (KeyError, TypeError, ValueError):
        return 1.0
