"""One table request: what to tabulate and how, validated once, with its cache key.

Every way of asking for a table reads into a ``TableRequest`` (``make`` or ``from_dict``):
the CLI (`bsdflab tabulate`), a job or HTTP request (``{"model", "grid", "rel_error", ...}``;
bsdflab.jobs.tabulate reads ``preset`` + ``overrides`` into the model first), and a
render's ``{"type": "tabulated", ...}`` material.
``bsdflab.tables.get`` turns one into a table (from the cache, or tabulated once).

The method: ``"auto"`` (the default) is adding-doubling wherever the solver covers the
model (a reflecting ``Layered`` stack in its validated range, bsdflab.solvers) and PFMC
otherwise; the request records which it chose and why (``method_note``). ``"pfmc"`` and
``"adding-doubling"`` ask for one (the latter refuses a model it does not cover).

The key (``key()``) hashes what determines the table's content (``content()``); it is the
key tables had before this type existed, so caches stay valid: a PFMC request holds the
walks' effort, seed, error floor and estimator version and no method entry; an
adding-doubling one the method and the solver's settings (``nodes`` and ``orders`` only
change them when given).
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

from bsdflab import _core
from bsdflab.bsdfs.base import BSDF, from_dict
from bsdflab.tables.channels import table_channels
from bsdflab.tables.data import DEFAULT_REL_ERROR, FORMAT_VERSION, TWO_SIDED_LOBES, TableGrid
from bsdflab.tables.file_format import canonical_json
from bsdflab.tables.stages import DEFAULT_MAX_SAMPLES, DEFAULT_MIN_SAMPLES, ERROR_FLOOR
from bsdflab.util import args as check

METHODS = ("pfmc", "adding-doubling")
CHOICES = ("auto", *METHODS)
FIELDS = ("model", "grid", "rel_error", "wavelengths", "min_samples", "max_samples",
          "seed", "method", "nodes", "orders")
TABULATED = "tabulated"  # a render material's tag for a table of its "model"


@dataclass(frozen=True)
class TableRequest:
    """A validated table request (build it with ``from_dict`` or ``make``).

    ``method`` is the method the table is made by ("pfmc" or "adding-doubling"), already
    resolved from "auto"; ``method_note`` says how it was chosen. ``min_samples``,
    ``max_samples`` and ``seed`` are PFMC's walk settings, ``nodes`` and ``orders`` the
    solver's (None: the table defaults, bsdflab.tables.deterministic)."""

    model: BSDF = field(compare=False)
    model_dict: dict[str, Any]
    grid: TableGrid
    rel_error: float
    wavelengths: tuple[float, ...] | None
    method: str
    method_note: str = field(compare=False)  # how the method was chosen: not part of the request
    min_samples: int
    max_samples: int
    seed: int
    nodes: int | None
    orders: int | None

    @classmethod
    def make(cls, model: BSDF, grid: TableGrid | dict[str, Any] | None = None,
             rel_error: float = DEFAULT_REL_ERROR, wavelengths=None, method: str = "auto",
             min_samples: int = DEFAULT_MIN_SAMPLES, max_samples: int = DEFAULT_MAX_SAMPLES,
             seed: int = 0, nodes: int | None = None, orders: int | None = None) -> TableRequest:
        """Validate every setting (ValueError naming the first bad one) and resolve the method."""
        if not isinstance(model, BSDF):
            raise ValueError(f"model must be a bsdflab BSDF, got {type(model).__name__} (from_dict reads dicts)")
        if grid is None:
            grid = TableGrid()
        elif isinstance(grid, dict):
            defaults = TableGrid().to_dict()
            grid = TableGrid.from_dict({**defaults, **grid})
        elif not isinstance(grid, TableGrid):
            raise ValueError(f"grid must be a TableGrid or a dict, got {type(grid).__name__}")
        rel_error = check.real_scalar("rel_error", rel_error, 0.0, 1.0, lo_open=True)
        if wavelengths is not None:
            wavelengths = tuple(float(w) for w in table_channels(check.wavelengths_nm("wavelengths", wavelengths))[1])
        min_samples = check.count("min_samples", min_samples)
        max_samples = check.count("max_samples", max_samples)
        if max_samples < min_samples:
            raise ValueError(f"max_samples ({max_samples}) must be >= min_samples ({min_samples})")
        seed = check.seed(seed)
        if nodes is not None:
            nodes = check.integer("nodes", nodes, 4, 256)
        if orders is not None:
            orders = check.integer("orders", orders, 1, 4096)
        method, note = resolve_method(model, method)
        if method == "pfmc" and (nodes is not None or orders is not None):
            raise ValueError("nodes and orders are the adding-doubling solver's settings; this table is "
                             f"made by PFMC ({note})")
        return cls(model, model.to_dict(), grid, rel_error, wavelengths, method, note, min_samples,
                   max_samples, seed, nodes, orders)

    @classmethod
    def from_dict(cls, d: dict[str, Any], **fixed) -> TableRequest:
        """A request from its dict form: a job's or HTTP request's (the FIELDS), a
        normalised one (``to_dict``), or a render's ``{"type": "tabulated", "model": ...}``
        material. ``fixed``: settings the caller decides, not read from ``d`` (a render's
        ``wavelengths``; ``model``, a BSDF, when the caller built it, e.g. from a preset)."""
        if not isinstance(d, dict):
            raise ValueError(f"a table request must be a dict, got {type(d).__name__}")
        d = dict(d)
        if d.get("type") == TABULATED:
            d.pop("type")
        unknown = set(d) - set(FIELDS)
        if unknown:
            raise ValueError(f"unknown table request fields: {', '.join(sorted(map(str, unknown)))} "
                             f"(known: {', '.join(FIELDS)})")
        model = fixed.pop("model", None)
        if model is None:
            if not isinstance(d.get("model"), dict):
                raise ValueError("a table request needs 'model', a BSDF dict")
            model = from_dict(d["model"])
        d.pop("model", None)
        if d.get("grid") is not None and not isinstance(d["grid"], dict):
            raise ValueError("grid must be a dict with n_theta_i, n_theta_o, n_phi, thickness_nm")
        settings = {k: v for k, v in d.items() if v is not None or k == "wavelengths"}
        return cls.make(model, **{**settings, **fixed})

    def to_dict(self) -> dict[str, Any]:
        """The normalised request (JSON; ``from_dict`` reads it back to an equal request)."""
        out = {"model": self.model_dict, "grid": self.grid.to_dict(), "rel_error": self.rel_error,
               "wavelengths": None if self.wavelengths is None else list(self.wavelengths),
               "method": self.method, "min_samples": self.min_samples, "max_samples": self.max_samples,
               "seed": self.seed}
        if self.nodes is not None or self.orders is not None:
            out.update({"nodes": self.nodes, "orders": self.orders})
        return out

    @property
    def channels(self) -> tuple[str, ...]:
        """The stored channels' names: R, G, B or the wavelengths as ``f"{nm:g}"``."""
        return table_channels(self.wavelengths)[0]

    def content(self) -> dict[str, Any]:
        """Everything that determines the table's content: the input of ``key``."""
        common = {"channels": list(self.channels), "format_version": FORMAT_VERSION,
                  "grid": self.grid.to_dict(), "model": self.model_dict, "rel_error": self.rel_error}
        if self.method == "adding-doubling":
            from bsdflab.tables.deterministic import solver_settings

            return {**common, "method": self.method, "solver": solver_settings(self.nodes, self.orders)}
        return {**common, "min_samples": self.min_samples, "max_samples": self.max_samples, "seed": self.seed,
                "error_floor": ERROR_FLOOR, "estimator_version": estimator_version()}

    def key(self) -> str:
        """The cache key: SHA-256 (hex) of the canonical JSON (sorted keys) of ``content()``."""
        try:
            text = canonical_json(self.content())
        except (TypeError, ValueError) as e:
            raise ValueError(f"cannot build a cache key: {e}") from None
        return hashlib.sha256(text.encode("utf-8")).hexdigest()

    def cells(self) -> int:
        """Table cells, a transmissive model's four lobes counted (an upper bound before
        the model is asked)."""
        return self.grid.cells(len(TWO_SIDED_LOBES))


def estimator_version() -> int:
    """The core's estimator version (changes whenever the same request gives other walks)."""
    return int(_core.estimator_version)


def resolve_method(model: BSDF, method: str) -> tuple[str, str]:
    """(the method a table of ``model`` is made by, how it was chosen) for ``method`` in
    CHOICES; ValueError for an unknown method or adding-doubling of a model it does not cover."""
    from bsdflab.tables.deterministic import adding_doubling_gap

    if not isinstance(method, str) or method not in CHOICES:
        raise ValueError(f"method must be one of {', '.join(CHOICES)}, got {check.brief(method)}")
    if method == "pfmc":
        return method, "asked for"
    gap = adding_doubling_gap(model)
    if method == "adding-doubling":
        if gap is not None:
            raise ValueError(f"method 'adding-doubling' cannot tabulate this model: {gap} (use method 'pfmc')")
        return method, "asked for"
    if gap is None:
        return "adding-doubling", "automatic: the solver covers this model"
    return "pfmc", f"automatic: adding-doubling does not cover this model ({gap})"

