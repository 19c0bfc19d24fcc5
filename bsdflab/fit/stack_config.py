"""Settings of a structure fit (a TOML with a ``[structure]`` table; docs/fit.md, "Structures
and instruments"):

    [structure]        exterior | layers | substrate (bsdflab.fit.structure)
    [instrument]       the instrument of the one dataset (bsdflab.fit.instrument), or
    [[dataset]]        co-refinement: name, data (a CSV path, relative to the config) and its
                       own [dataset.instrument]; the structure's parameters are shared
    [parameters]       priors or fixed values of the structure's parameters and noise_scale
    [model]            bandwidth_nodes, cone_nodes, cone_azimuths (the instrument's quadratures),
                   thickness_nodes (the layers' thickness spreads)
    [sampler]          as fit.toml (bsdflab.fit.config.SamplerSettings)
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

from bsdflab.fit import parameters as P
from bsdflab.fit.config import AppearanceSettings, OutputSettings, SamplerSettings, _settings, _table, load_toml
from bsdflab.fit.instrument import Instrument
from bsdflab.fit.priors import Prior
from bsdflab.fit.stack_forward import BANDWIDTH_NODES, CONE_AZIMUTHS, CONE_NODES
from bsdflab.fit.structure import Structure
from bsdflab.fit.thickness_spread import THICKNESS_NODES, check_spread_cost

_DATASET = re.compile(r"^[a-z][a-z0-9_]{0,31}$")


@dataclass(frozen=True)
class StackModelSettings:
    bandwidth_nodes: int = BANDWIDTH_NODES
    cone_nodes: int = CONE_NODES
    cone_azimuths: int = CONE_AZIMUTHS
    thickness_nodes: int = THICKNESS_NODES

    @classmethod
    def parse(cls, d: dict) -> StackModelSettings:
        d = {k: v for k, v in _table("model", d).items() if k != "kind" or v != "stack"}
        s = cls(**_settings(cls, "model", d, {"bandwidth_nodes": (1, 63), "cone_nodes": (1, 64),
                                              "cone_azimuths": (1, 64), "thickness_nodes": (1, 64)}))
        if s.bandwidth_nodes % 2 == 0:
            raise ValueError(f"[model] bandwidth_nodes must be odd (the middle node is the nominal "
                             f"wavelength), got {s.bandwidth_nodes}")
        return s


@dataclass(frozen=True)
class DatasetSpec:
    name: str                 # "" for the one dataset of a config without [[dataset]]
    data: str | None          # CSV path (None: given on the command line)
    instrument: Instrument

    def prefix(self, name: str) -> str:
        return f"{self.name}.{name}" if self.name else name


@dataclass(frozen=True)
class StackConfig:
    structure: Structure
    datasets: tuple[DatasetSpec, ...]
    priors: dict[str, Prior]          # the structure's parameters and noise_scale
    fixed: dict[str, float]
    sampler: SamplerSettings = SamplerSettings()
    model: StackModelSettings = StackModelSettings()
    appearance: AppearanceSettings = AppearanceSettings()
    source: str = ""
    output: OutputSettings = OutputSettings()

    @classmethod
    def parse(cls, d: dict, source: str = "") -> StackConfig:
        known = {"structure", "instrument", "dataset", "parameters", "model", "sampler", "appearance", "output"}
        unknown = set(d) - known
        if unknown:
            raise ValueError(f"top level: unknown key(s) {', '.join(sorted(unknown))}; "
                             f"known: {', '.join(sorted(known))}")
        structure = Structure.parse(d.get("structure"))
        base = os.path.dirname(os.path.abspath(source)) if source else os.getcwd()
        specs = _dataset_specs(d, base)
        params = d.get("parameters", {})
        if not isinstance(params, dict):
            raise ValueError("[parameters] must be a table")
        table = {p.name: p for p in (*structure.parameters(), P.NOISE)}
        priors, fixed = {}, {}
        for name, spec in params.items():
            if name not in table:
                raise ValueError(f"[parameters] {name!r} is not a parameter of this structure; its parameters: "
                                 f"{', '.join(table)} (instrument parameters go in [instrument])")
            if isinstance(spec, dict) and set(spec) == {"fixed"}:
                spec = spec["fixed"]
            if isinstance(spec, dict):
                priors[name] = Prior.make(name, spec)
                continue
            ok = isinstance(spec, (int, float)) and not isinstance(spec, bool) and math.isfinite(spec)
            p = table[name]
            if not ok or not in_domain(p, spec):
                raise ValueError(f"[parameters] {name}: fixed value must be a number in [{p.lo:g}, {p.hi:g}], "
                                 f"got {spec!r}")
            fixed[name] = float(spec)
        for name, p in table.items():
            if name not in priors and name not in fixed:
                fixed[name] = p.default
        if not priors and not any(s.instrument.priors for s in specs):
            raise ValueError("no free parameter: give at least one a prior")
        sampler = SamplerSettings.parse(d.get("sampler", {}))
        model = StackModelSettings.parse(d.get("model", {}))
        # the spreads that can be non-zero cost thickness_nodes^m sets each (a fixed 0 costs nothing)
        spread = [structure.layers[i].name for i in structure.spread_layers()]
        check_spread_cost(model.thickness_nodes,
                          [n for n in spread if fixed.get(f"{n}_thickness_spread_nm", 1.0) != 0.0])
        return cls(structure, tuple(specs), priors, fixed, sampler, model,
                   AppearanceSettings.parse(d.get("appearance", {})), source, OutputSettings.parse(d.get("output", {})))

    @classmethod
    def load(cls, path: str | os.PathLike) -> StackConfig:
        path = os.fspath(path)
        try:
            return cls.parse(load_toml(path), source=path)
        except ValueError as e:
            msg = str(e)
            raise ValueError(msg if msg.startswith(path) else f"{path}: {msg}") from None


def _dataset_specs(d: dict, base: str) -> list[DatasetSpec]:
    """The [[dataset]] entries (paths relative to ``base``), or the one dataset of [instrument]."""
    if "dataset" in d:
        if "instrument" in d:
            raise ValueError("give the instrument per dataset ([dataset.instrument]) when [[dataset]] is used, "
                             "not [instrument]")
        entries = d["dataset"]
        if not isinstance(entries, list) or not entries:
            raise ValueError("[[dataset]] must be a non-empty array of tables")
        specs, names = [], set()
        for i, e in enumerate(entries):
            where = f"[[dataset]] {i}"
            if not isinstance(e, dict) or set(e) - {"name", "data", "instrument"} or not {"name", "data"} <= set(e):
                raise ValueError(f"{where}: takes name, data and an optional instrument table")
            name, data = e["name"], e["data"]
            if not isinstance(name, str) or not _DATASET.match(name) or name in names:
                raise ValueError(f"{where}: name must be a new lower-case identifier, got {name!r}")
            if not isinstance(data, str) or not data:
                raise ValueError(f"{where}: data must be a CSV path, got {data!r}")
            names.add(name)
            specs.append(DatasetSpec(name, os.path.join(base, data),
                                     Instrument.parse(f"dataset.{name}.instrument", e.get("instrument", {}))))
    else:
        specs = [DatasetSpec("", None, Instrument.parse("instrument", d.get("instrument", {})))]
    return specs


def is_stack_config(d: dict) -> bool:
    """A parsed TOML is a structure fit when it has a [structure] table."""
    return "structure" in d


def in_domain(p: P.Parameter, value: float) -> bool:
    return bool((value > p.lo if p.lo_open else value >= p.lo) and value <= p.hi)
