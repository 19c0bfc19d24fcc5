"""The in-memory form of a BSDF table (what a table file holds).

Axes (all angles in radians):
  lobe       "reflection" (wo above the surface) and, for models that transmit,
             "transmission" (wo below; theta_o measured from -z), "reflection_below"
             (wi and wo below) and "transmission_below" (wi below, wo above): light
             from below (format version 3; version 1-2 files hold the first two only)
  thickness  film-thickness nodes in nm (empty: the model's own thickness only)
  theta_i    incidence nodes, cell centres of n equal steps over [0, pi/2]
  theta_o    outgoing nodes, the same scheme
  phi        |phi_o - phi_i| nodes, evenly spaced over [0, pi] both ends included
             (isotropic models are symmetric under phi -> -phi)
  channel    "R", "G", "B" (linear sRGB, D65) or wavelengths in nm

``values`` holds the BSDF value f(wi, wo) -- without the cosine -- of the *tabulated part*.
When ``split_direct`` is True (layered models), the top interface's own reflection is not
in the table: it is evaluated exactly from the model's ``exact_part`` (the top interface)
at lookup time, and so is the top's delta reflection. Otherwise the table holds the whole non-delta BSDF.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsdflab.bsdfs.base import from_dict
from bsdflab.lobes import Lobe
from bsdflab.tables.channels import LUMINANCE_RGB
from bsdflab.tables.coverage import coverage_record
from bsdflab.util import args as check
from bsdflab.util import limits

# 3: transmissive models hold four lobes (light from both sides); 2: optional keyed
# signature (bsdflab.signature); 1 and 2 are still read.
FORMAT_VERSION = 3
LOBES = ("reflection", "transmission")  # light from above (all a version 1-2 file holds)
TWO_SIDED_LOBES = (*LOBES, "reflection_below", "transmission_below")
LOBE_SETS = (LOBES[:1], LOBES, TWO_SIDED_LOBES)  # opaque; transmissive, above only; both sides
MAX_NODES = 512
MAX_THICKNESS_NODES = 256
# RGB tables may hold slightly negative channels (saturated spectra lie outside the sRGB
# gamut), never a negative luminance beyond float32 rounding of the projection.
LUMINANCE_TOLERANCE = 1e-5


def node_centres(n: int) -> np.ndarray:
    """n cell-centred angles over [0, pi/2] (never exactly normal or grazing)."""
    return (np.arange(n) + 0.5) * (0.5 * np.pi / n)


DEFAULT_REL_ERROR = 0.01  # the one default target of a table (docs/table_format.md, "Target met")


def check_table_memory(grid: TableGrid, n_channels: int, n_lobes: int = len(TWO_SIDED_LOBES)) -> None:
    """Refuse a table on ``grid`` whose estimated memory exceeds ``BSDFLAB_MAX_BYTES``
    (call before tabulating; ``n_lobes`` 4 covers transmissive models, two-sided)."""
    cells = grid.cells(n_lobes)
    limits.check_bytes(f"a table of {cells} cells x {n_channels} channels", limits.table_bytes(cells, n_channels))


@dataclass(frozen=True)
class TableGrid:
    """Resolution of a table. Defaults balance accuracy and tabulation time for the
    xenopeltis preset (see README, Tabulation)."""

    n_theta_i: int = 12
    n_theta_o: int = 24
    n_phi: int = 13
    thickness_nm: tuple[float, ...] = ()

    def __post_init__(self):
        for name in ("n_theta_i", "n_theta_o", "n_phi"):
            object.__setattr__(self, name, check.integer(name, getattr(self, name), 2, MAX_NODES))
        if not isinstance(self.thickness_nm, (list, tuple, np.ndarray)):
            raise ValueError(f"thickness_nm must be a list of nm values, got {check.brief(self.thickness_nm)}")
        if len(self.thickness_nm) > MAX_THICKNESS_NODES:
            raise ValueError(f"thickness_nm must have at most {MAX_THICKNESS_NODES} nodes, "
                             f"got {len(self.thickness_nm)}")
        nodes = check.film_thickness("thickness_nm", list(self.thickness_nm), array=True, ndim=1) \
            if len(self.thickness_nm) else ()
        t = tuple(float(x) for x in nodes)
        if list(t) != sorted(set(t)):
            raise ValueError("thickness_nm must be strictly increasing")
        object.__setattr__(self, "thickness_nm", t)
        limits.check_count(f"table grid cells ({len(TWO_SIDED_LOBES)} lobes x thickness nodes x theta_i x "
                           "theta_o x phi)", self.cells(len(TWO_SIDED_LOBES)), "BSDFLAB_MAX_TABLE_CELLS")

    def cells(self, n_lobes: int = 1) -> int:
        """Cells of a table on this grid with ``n_lobes`` lobes."""
        return n_lobes * max(1, len(self.thickness_nm)) * self.n_theta_i * self.n_theta_o * self.n_phi

    @property
    def theta_i(self) -> np.ndarray:
        return node_centres(self.n_theta_i)

    @property
    def theta_o(self) -> np.ndarray:
        return node_centres(self.n_theta_o)

    @property
    def phi(self) -> np.ndarray:
        return np.linspace(0.0, np.pi, self.n_phi)

    def to_dict(self) -> dict[str, Any]:
        return {"n_theta_i": self.n_theta_i, "n_theta_o": self.n_theta_o, "n_phi": self.n_phi,
                "thickness_nm": list(self.thickness_nm)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TableGrid:
        if not isinstance(d, dict):
            raise ValueError(f"a table grid must be a dict, got {type(d).__name__}")
        unknown = set(d) - {"n_theta_i", "n_theta_o", "n_phi", "thickness_nm"}
        if unknown:
            raise ValueError(f"unknown table grid keys: {', '.join(sorted(map(str, unknown)))}")
        missing = [k for k in ("n_theta_i", "n_theta_o", "n_phi") if k not in d]
        if missing:
            raise ValueError(f"a table grid needs {', '.join(missing)}")
        return cls(d["n_theta_i"], d["n_theta_o"], d["n_phi"], d.get("thickness_nm", ()))


@dataclass
class TableData:
    model: dict[str, Any]
    grid: TableGrid
    lobes: tuple[str, ...]
    channels: tuple[str, ...]           # ("R", "G", "B") or wavelengths as strings
    split_direct: bool
    values: np.ndarray                  # float32 (n_lobe, n_t, n_ti, n_to, n_phi, C), f without cos
    stderr: np.ndarray                  # float32, same shape: standard error of values
    samples: np.ndarray                 # int32 (n_lobe, n_t, n_ti, n_to, n_phi): walks per cell
    rel_error_target: float
    meta: dict[str, Any] = field(default_factory=dict)  # version, timings, achieved error...

    @property
    def n_thickness(self) -> int:
        return max(1, len(self.grid.thickness_nm))

    @property
    def two_sided(self) -> bool:
        """Whether the table holds light arriving from below too (four lobes)."""
        return self.lobes == TWO_SIDED_LOBES

    def sides(self) -> str:
        """Which light the table describes, in words (``table info``)."""
        if self.two_sided:
            return "from both sides (reflection and transmission from above and from below)"
        if len(self.lobes) == 2:
            return "from above only (reflection, transmission; a format version 1-2 table)"
        return "from above (reflection; the model is opaque)"

    @property
    def spectral(self) -> bool:
        return self.channels != ("R", "G", "B")

    def shape(self) -> tuple[int, ...]:
        g = self.grid
        return (len(self.lobes), self.n_thickness, g.n_theta_i, g.n_theta_o, g.n_phi, len(self.channels))

    def check(self) -> None:
        """Raise ValueError if the arrays do not match the grid, lobes and channels."""
        shape = self.shape()
        if self.values.shape != shape or self.stderr.shape != shape:
            raise ValueError(f"table values/stderr have shape {self.values.shape}/{self.stderr.shape}, "
                             f"expected {shape} from the grid, lobes and channels")
        if self.samples.shape != shape[:-1]:
            raise ValueError(f"table samples have shape {self.samples.shape}, expected {shape[:-1]}")
        if self.lobes not in LOBE_SETS:
            raise ValueError(f"table lobes must be one of {', '.join(map(str, LOBE_SETS))}, got {self.lobes}")
        if not np.all(np.isfinite(self.values)) or not np.all(np.isfinite(self.stderr)):
            raise ValueError("table values must be finite")
        if np.any(self.stderr < 0):
            raise ValueError("table standard errors must be >= 0")
        if self.samples.size and int(self.samples.min()) < 1:
            raise ValueError(f"every table cell must have >= 1 sample, found {int(self.samples.min())}")
        self._check_signs()
        rel = self.rel_error_target
        if isinstance(rel, bool) or not isinstance(rel, (int, float)) or not 0 < rel <= 1:
            raise ValueError(f"table rel_error_target must be a number in (0, 1], got {rel!r}")
        if not isinstance(self.split_direct, bool):
            raise ValueError("table split_direct must be a boolean")

    def _check_signs(self) -> None:
        if self.spectral:
            if np.any(self.values < 0):
                raise ValueError("spectral table values must be >= 0 (a BSDF is never negative)")
            return
        lum = self.values.astype(np.float64) @ LUMINANCE_RGB
        floor = -LUMINANCE_TOLERANCE * max(1.0, float(np.abs(lum).max(initial=0.0)))
        if lum.size and float(lum.min()) < floor:
            raise ValueError(f"table luminance must be >= 0 (a BSDF is never negative), found {lum.min():g}")

    def accuracy(self) -> dict[str, Any]:
        """Whether the table meets its target, and the figures that decide it: the one
        definition of "target met" is in bsdflab.tables.summary (the 95th percentile of the
        cells' relative error of luminance at most ``rel_error_target``; the max beside it).
        ``coverage`` (PFMC tables): how often cell errors were exceeded by k sigma in the
        coverage study of the table's estimator version (bsdflab.tables.coverage,
        docs/coverage.md), None where that version was not measured or the table is not PFMC;
        its ``applies`` is False, with a ``warning``, for a pilot shorter than the measured one."""
        from bsdflab.tables.summary import STDERR, accuracy

        a = accuracy(self)
        a["coverage"] = (coverage_record(self.meta.get("estimator_version"), self.meta.get("min_samples"))
                         if a["kind"] == STDERR else None)
        return a

    def check_model(self):
        """The table's model rebuilt through ``from_dict`` (ValueError when it is not a
        valid model), checked against the table: layered models are split, and the
        transmission lobes are there exactly when the model transmits (two of them in a
        version 1-2 table, light from above only; four since version 3)."""
        model = from_dict(self.model)
        layered = model.type_name == "layered"
        if self.split_direct != layered:
            raise ValueError(f"split_direct is {self.split_direct} but the model is "
                             f"{'' if layered else 'not '}layered")
        transmits = bool(model.lobes & Lobe.TRANSMISSION)
        if (len(self.lobes) > 1) != transmits:
            raise ValueError(f"the table has lobes {self.lobes} but the model "
                             f"{'transmits' if transmits else 'does not transmit'}")
        return model
