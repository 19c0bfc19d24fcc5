"""The fit's structure as a stack (refnx's ``air | slab | slab | substrate``, Nelson &
Prescott 2019): an exterior, layers of named materials and thicknesses (periodic blocks
repeat their layers ``periods`` times with shared parameters), a substrate (absorbing
allowed). TOML (docs/fit.md, "Structures"):

    [structure]
    exterior = "air"
    substrate = "keratin"            # a named material (bsdflab.fit.materials), a number,
                                     # {n, k} or {cauchy = [A, B(, C)], k}
    [[structure.layers]]
    name = "film"                    # its parameters: film_thickness_nm (+ film_ior, ...)
    material = "guanine"
    thickness_nm = 400.0
    thickness_spread_nm = 0.0        # optional: film_thickness_spread_nm (bsdflab.fit.thickness_spread)
    [[structure.layers]]             # a periodic multilayer
    periods = 5
    layers = [{ name = "platelet", material = "guanine", thickness_nm = 80.0 },
              { name = "gap", material = "cytoplasm", thickness_nm = 100.0 }]

Parameters: ``<layer>_thickness_nm`` for every layer, ``<layer>_thickness_spread_nm`` for a
layer that declares ``thickness_spread_nm`` (the sd of its thickness over the spot; every
period of a block shares one draw), and for a medium written as numbers
its coefficients ``<medium>_ior`` (n or Cauchy A), ``<medium>_cauchy_b``, ``<medium>_cauchy_c``,
``<medium>_k`` (the exterior has no k: the incident medium must be lossless). The film's
index may lie above or below the substrate's.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from bsdflab.fit.materials import Material, material
from bsdflab.fit.parameters import Parameter

MAX_LAYERS = 64          # after expanding the periods (the core's stack limit)
MAX_SPREAD_NM = 1e4      # a layer's thickness spread (sd), nm
_NAME = re.compile(r"^[a-z][a-z0-9_]{0,31}$")


@dataclass(frozen=True)
class Medium:
    name: str            # prefix of its parameters
    material: Material


@dataclass(frozen=True)
class Structure:
    exterior: Medium
    layers: tuple[Medium, ...]          # distinct layers (each once)
    thickness_nm: tuple[float, ...]     # their default thicknesses
    spread_nm: tuple[float | None, ...]  # their default thickness spreads (None: not declared, exact)
    order: tuple[int, ...]              # the stack top to bottom, as indices into layers
    substrate: Medium

    @property
    def media(self) -> tuple[Medium, ...]:
        return (self.exterior, *self.layers, self.substrate)

    def parameters(self) -> tuple[Parameter, ...]:
        out = []
        for layer, d in zip(self.layers, self.thickness_nm):
            out.append(Parameter(f"{layer.name}_thickness_nm", "nm", d, 0.0, 1e5,
                                 f"thickness of the {layer.name} layer ({layer.material.label})"))
        for layer, sd in zip(self.layers, self.spread_nm):
            if sd is not None:
                out.append(Parameter(f"{layer.name}_thickness_spread_nm", "nm", sd, 0.0, MAX_SPREAD_NM,
                                     f"sd of the {layer.name} layer's thickness over the spot"))
        for m in self.media:
            for c in m.material.coefficients():
                if m is self.exterior and c.key != "ior":
                    continue
                out.append(Parameter(f"{m.name}_{c.key}", "", c.default, c.lo, c.hi, f"{m.name}: {c.description}",
                                     lo_open=c.key == "ior"))
        return tuple(out)

    def arrays(self, value, wl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n (P, media of the stack, E) complex, d (P, stack layers)) for parameter sets;
        ``value(name)`` gives a parameter's (P,) values, ``wl`` (P, E) in nm."""
        def index(m: Medium) -> np.ndarray:
            keys = [c.key for c in m.material.coefficients() if m is not self.exterior or c.key == "ior"]
            return m.material.index({k: value(f"{m.name}_{k}") for k in keys}, wl)
        layer_n = [index(m) for m in self.layers]
        n = np.stack([index(self.exterior), *(layer_n[i] for i in self.order), index(self.substrate)], axis=1)
        thick = [value(f"{m.name}_thickness_nm") for m in self.layers]
        d = np.stack([thick[i] for i in self.order], axis=1) if self.order else np.zeros((len(wl), 0))
        return n, d

    def spread_layers(self) -> tuple[int, ...]:
        """Indices into ``layers`` of the layers with a thickness spread parameter."""
        return tuple(i for i, sd in enumerate(self.spread_nm) if sd is not None)

    @classmethod
    def parse(cls, d: dict) -> Structure:
        if not isinstance(d, dict):
            raise ValueError("[structure] must be a table")
        unknown = set(d) - {"exterior", "substrate", "layers"}
        if unknown:
            raise ValueError(f"[structure]: unknown key(s) {', '.join(sorted(unknown))}; "
                             "known: exterior, substrate, layers")
        exterior = Medium("exterior", material("[structure] exterior", d.get("exterior", "air")))
        if exterior.material.k or exterior.material.k_amp:
            raise ValueError("[structure] exterior must be lossless (k = 0): light arrives through it")
        if "substrate" not in d:
            raise ValueError("[structure] needs substrate = a material")
        substrate = Medium("substrate", material("[structure] substrate", d["substrate"]))
        entries = d.get("layers", [])
        if not isinstance(entries, list):
            raise ValueError("[structure] layers must be an array of tables ([[structure.layers]])")
        layers, thickness, spread, order, names = [], [], [], [], {"exterior", "substrate"}

        def add(where, e) -> int:
            medium, t, sd = _layer(where, e, names)
            layers.append(medium)
            thickness.append(t)
            spread.append(sd)
            return len(layers) - 1

        for i, e in enumerate(entries):
            where = f"[structure] layers[{i}]"
            if isinstance(e, dict) and "periods" in e:
                periods, block = _block(where, e)
                order += [add(f"{where} layers[{j}]", b) for j, b in enumerate(block)] * periods
            else:
                order.append(add(where, e))
        if len(order) > MAX_LAYERS:
            raise ValueError(f"[structure]: {len(order)} layers after the periods; at most {MAX_LAYERS}")
        return cls(exterior, tuple(layers), tuple(thickness), tuple(spread), tuple(order), substrate)


def _layer(where: str, e, names: set) -> tuple[Medium, float, float | None]:
    """One layer table (name, material, thickness_nm, optional thickness_spread_nm); its name
    joins ``names``."""
    if not isinstance(e, dict):
        raise ValueError(f"{where} must be a table")
    extra = set(e) - {"name", "material", "thickness_nm", "thickness_spread_nm"}
    if extra or not {"name", "material", "thickness_nm"} <= set(e):
        raise ValueError(f"{where} takes name, material, thickness_nm and optionally thickness_spread_nm, "
                         f"got keys {sorted(e)}")
    name = e["name"]
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(f"{where}: name must be lower-case letters, digits, _ (a letter first), got {name!r}")
    if name in names:
        raise ValueError(f"{where}: name {name!r} is used twice (layers share parameters by "
                         "repeating inside a periodic block, not by name)")
    names.add(name)
    t = e["thickness_nm"]
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t) or not 0 <= t <= 1e5:
        raise ValueError(f"{where}: thickness_nm must be a number in [0, 1e5], got {t!r}")
    sd = e.get("thickness_spread_nm")
    if sd is not None and (isinstance(sd, bool) or not isinstance(sd, (int, float)) or not math.isfinite(sd)
                           or not 0 <= sd <= MAX_SPREAD_NM):
        raise ValueError(f"{where}: thickness_spread_nm must be a number in [0, {MAX_SPREAD_NM:g}], got {sd!r}")
    return Medium(name, material(f"{where} material", e["material"])), float(t), None if sd is None else float(sd)


def _block(where: str, e: dict) -> tuple[int, list]:
    """A periodic block's (periods, layer tables)."""
    if set(e) - {"periods", "layers"}:
        raise ValueError(f"{where}: a periodic block takes periods and layers, got keys {sorted(e)}")
    p = e["periods"]
    if isinstance(p, bool) or not isinstance(p, int) or not 1 <= p <= MAX_LAYERS:
        raise ValueError(f"{where}: periods must be an integer in [1, {MAX_LAYERS}], got {p!r}")
    block = e.get("layers")
    if not isinstance(block, list) or not block:
        raise ValueError(f"{where}: layers must be a non-empty list of layer tables")
    return p, block
