"""Settings of a full-model structure fit: a TOML with ``[structure]`` (plus its slab and
base, bsdflab.fit.full_structure) and ``[model] kind = "full"`` (docs/fit.md, "Structures
for the full model"). The other tables are a structure fit's (bsdflab.fit.stack_config):
``[instrument]`` or ``[[dataset]]`` with ``[dataset.instrument]``, ``[parameters]``,
``[sampler]``, ``[appearance]``. ``[model]``: kind, nodes, orders (the solver's),
emulator_nodes, emulator_checks (as the snake's full model), bandwidth_nodes, cone_nodes,
cone_azimuths (the instrument's quadrature).

The instrument on gonio rows: ``scale`` (per dataset or per series), ``background``, and
the quadrature's terms (bsdflab.fit.gonio_instrument): ``angle_offset_deg`` (a sample tilt
about the axis normal to the plane of incidence), ``acceptance_deg`` (the illumination
cone) and ``bandwidth_nm`` (the Gaussian slit), each off unless given; ``[model]``
bandwidth_nodes, cone_nodes and cone_azimuths size their quadrature as the smooth model's.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from bsdflab.fit import parameters as P
from bsdflab.fit.config import AppearanceSettings, OutputSettings, SamplerSettings, _settings, load_toml
from bsdflab.fit.full_structure import FullStructure
from bsdflab.fit.priors import Prior
from bsdflab.fit.stack_config import DatasetSpec, StackConfig, _dataset_specs, in_domain
from bsdflab.fit.stack_forward import BANDWIDTH_NODES, CONE_AZIMUTHS, CONE_NODES


@dataclass(frozen=True)
class FullStackModelSettings:
    kind: str = "full"
    nodes: int = 16
    orders: int = 0
    emulator_nodes: int = 5
    emulator_checks: int = 2
    bandwidth_nodes: int = BANDWIDTH_NODES  # the instrument's quadrature, as the smooth model's
    cone_nodes: int = CONE_NODES
    cone_azimuths: int = CONE_AZIMUTHS  # over [0, pi]; gonio rows take twice as many over [0, 2 pi)

    @classmethod
    def parse(cls, d: dict) -> FullStackModelSettings:
        if not isinstance(d, dict):
            raise ValueError("[model] must be a table")
        s = cls(
            **_settings(
                cls,
                "model",
                {k: v for k, v in d.items() if k != "kind"},
                {
                    "nodes": (4, 256),
                    "orders": (0, 4096),
                    "emulator_nodes": (0, 64),
                    "emulator_checks": (0, 1000),
                    "bandwidth_nodes": (1, 63),
                    "cone_nodes": (1, 64),
                    "cone_azimuths": (1, 64),
                },
            )
        )
        if s.bandwidth_nodes % 2 == 0:
            raise ValueError(
                f"[model] bandwidth_nodes must be odd (the middle node is the nominal wavelength), "
                f"got {s.bandwidth_nodes}"
            )
        return s


@dataclass(frozen=True)
class FullStackConfig:
    structure: FullStructure
    datasets: tuple[DatasetSpec, ...]
    priors: dict[str, Prior]
    fixed: dict[str, float]
    sampler: SamplerSettings = SamplerSettings()
    model: FullStackModelSettings = FullStackModelSettings()
    appearance: AppearanceSettings = AppearanceSettings()
    source: str = ""
    output: OutputSettings = OutputSettings()

    @classmethod
    def parse(cls, d: dict, source: str = "") -> FullStackConfig:
        known = {"structure", "instrument", "dataset", "parameters", "model", "sampler", "appearance", "output"}
        unknown = set(d) - known
        if unknown:
            raise ValueError(
                f"top level: unknown key(s) {', '.join(sorted(unknown))}; known: {', '.join(sorted(known))}"
            )
        structure = FullStructure.parse(d.get("structure"))
        base = os.path.dirname(os.path.abspath(source)) if source else os.getcwd()
        specs = _dataset_specs(d, base)
        params = d.get("parameters", {})
        if not isinstance(params, dict):
            raise ValueError("[parameters] must be a table")
        table = {p.name: p for p in (*structure.parameters(), P.NOISE)}
        priors, fixed = {}, {}
        for name, spec in params.items():
            if name not in table:
                raise ValueError(
                    f"[parameters] {name!r} is not a parameter of this structure; its parameters: "
                    f"{', '.join(table)} (instrument parameters go in [instrument])"
                )
            if isinstance(spec, dict) and set(spec) == {"fixed"}:
                spec = spec["fixed"]
            if isinstance(spec, dict):
                priors[name] = Prior.make(name, spec)
                continue
            ok = isinstance(spec, (int, float)) and not isinstance(spec, bool) and math.isfinite(spec)
            p = table[name]
            if not ok or not in_domain(p, spec):
                raise ValueError(
                    f"[parameters] {name}: fixed value must be a number in [{p.lo:g}, {p.hi:g}], got {spec!r}"
                )
            fixed[name] = float(spec)
        for name, p in table.items():
            if name not in priors and name not in fixed:
                fixed[name] = p.default
        if not priors and not any(s.instrument.priors for s in specs):
            raise ValueError("no free parameter: give at least one a prior")
        return cls(
            structure,
            tuple(specs),
            priors,
            fixed,
            SamplerSettings.parse(d.get("sampler", {})),
            FullStackModelSettings.parse(d.get("model", {})),
            AppearanceSettings.parse(d.get("appearance", {})),
            source,
            OutputSettings.parse(d.get("output", {})),
        )


def is_full(d: dict) -> bool:
    """A parsed structure TOML asks for the full model."""
    model = d.get("model", {})
    return isinstance(model, dict) and model.get("kind") == "full"


def parse_structure_config(d: dict, source: str = ""):
    """A structure fit's config: FullStackConfig for [model] kind = "full", else StackConfig."""
    if is_full(d):
        return FullStackConfig.parse(d, source)
    s = d.get("structure")
    if isinstance(s, dict):
        for key in ("slab", "base", "interface"):
            if key in s:
                raise ValueError(
                    f"[structure] {key} needs [model] kind = 'full' (the smooth stack model has no "
                    "slab, base or rough interface)"
                )
    return StackConfig.parse(d, source)


def load_structure_config(path: str | os.PathLike):
    path = os.fspath(path)
    try:
        return parse_structure_config(load_toml(path), source=path)
    except ValueError as e:
        msg = str(e)
        raise ValueError(msg if msg.startswith(path) else f"{path}: {msg}") from None
