"""The in-memory form of a BSDF table (what a table file holds).

Axes (all angles in radians):
  lobe       "reflection" (wo above the surface) and, for models that transmit,
             "transmission" (wo below; theta_o measured from -z)
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

FORMAT_VERSION = 1
LOBES = ("reflection", "transmission")


def node_centres(n: int) -> np.ndarray:
    """n cell-centred angles over [0, pi/2] (never exactly normal or grazing)."""
    return (np.arange(n) + 0.5) * (0.5 * np.pi / n)


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
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 2 <= v <= 512:
                raise ValueError(f"{name} must be an integer in [2, 512], got {v!r}")
        t = tuple(float(x) for x in self.thickness_nm)
        if any(not np.isfinite(x) or x < 0 for x in t) or list(t) != sorted(set(t)):
            raise ValueError("thickness_nm must be finite, >= 0 and strictly increasing")
        object.__setattr__(self, "thickness_nm", t)

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
    def from_dict(cls, d: dict[str, Any]) -> "TableGrid":
        return cls(d["n_theta_i"], d["n_theta_o"], d["n_phi"], tuple(d.get("thickness_nm", ())))


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
        if any(l not in LOBES for l in self.lobes) or not self.lobes or self.lobes[0] != "reflection":
            raise ValueError(f"table lobes must be ('reflection',) or ('reflection', 'transmission'), got {self.lobes}")
        if not np.all(np.isfinite(self.values)) or not np.all(np.isfinite(self.stderr)):
            raise ValueError("table values must be finite")
