"""Fit and simulation settings from TOML files (stdlib ``tomllib``; docs/fit_data.md).

fit.toml
    [parameters]   one entry per parameter: a prior (bsdflab.fit.priors) or a fixed value;
                   parameters left out are fixed at their defaults (bsdflab.fit.parameters)
    [sampler]      walkers, max_steps (the step cap), tau_multiple (run until
                   N > tau_multiple * tau), check_every, seed, map_starts
    [model]        thickness_nodes, angle_nodes (quadrature orders)
    [appearance]   draws, angles_deg, renders, render_size, render_spp
truth.toml (``bsdflab fit simulate``)
    [truth]        parameter values (missing ones: defaults)
    [noise]        relative, absolute, seed: sigma_i = sqrt(absolute^2 + (relative y_i)^2)
    [[measurement]] geometry, angles_deg (or angle_pairs_deg for diffuse), wavelengths_nm
                   ({start, stop, step} or a list)
    [model]        as above
"""
from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass, field

import numpy as np

from bsdflab.fit import parameters as P
from bsdflab.fit.priors import Prior

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def load_toml(path: str | os.PathLike) -> dict:
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError as e:
        raise ValueError(f"cannot read config file {path}: {e}") from None
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{path}: not valid TOML: {e}") from None


def _check_keys(section: str, given: dict, known: dict) -> None:
    unknown = sorted(set(given) - set(known))
    if unknown:
        raise ValueError(f"[{section}]: unknown key(s) {', '.join(unknown)}; known: {', '.join(known)}")


def _integer(section: str, key: str, value, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise ValueError(f"[{section}] {key} must be an integer in [{lo}, {hi}], got {value!r}")
    return value


def _real(section: str, key: str, value, lo: float, hi: float = math.inf, lo_open=False) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < lo or (lo_open and value == lo) or value > hi:
        raise ValueError(f"[{section}] {key} must be a finite number in {'(' if lo_open else '['}{lo:g}, {hi:g}], "
                         f"got {value!r}")
    return float(value)


def _settings(cls, section: str, d: dict, ranges: dict) -> dict:
    """Values of the keys in ``ranges`` ({key: (lo, hi)}; float bounds mean a real number)
    from table ``d``, each defaulting to the dataclass ``cls``'s default."""
    _check_keys(section, d, cls.__dataclass_fields__)
    base, out = cls(), {}
    for key, (lo, hi) in ranges.items():
        v = d.get(key, getattr(base, key))
        out[key] = _real(section, key, v, lo, hi) if isinstance(lo, float) else _integer(section, key, v, lo, hi)
    return out


@dataclass(frozen=True)
class ModelSettings:
    thickness_nodes: int = 24
    angle_nodes: int = 32

    @classmethod
    def parse(cls, d: dict) -> ModelSettings:
        return cls(**_settings(cls, "model", d, {"thickness_nodes": (1, 200), "angle_nodes": (2, 1000)}))


@dataclass(frozen=True)
class SamplerSettings:
    walkers: int = 32
    max_steps: int = 20000
    tau_multiple: float = 50.0
    check_every: int = 200
    seed: int = 0
    map_starts: int = 8

    @classmethod
    def parse(cls, d: dict) -> SamplerSettings:
        s = cls(**_settings(cls, "sampler", d, {
            "walkers": (4, 10000), "max_steps": (10, 10_000_000), "tau_multiple": (1.0, math.inf),
            "check_every": (10, 1_000_000), "seed": (0, 2**63 - 1), "map_starts": (1, 1000)}))
        if s.walkers % 2:
            raise ValueError(f"[sampler] walkers must be even (emcee's stretch move), got {s.walkers}")
        return s


@dataclass(frozen=True)
class AppearanceSettings:
    draws: int = 48
    angles_deg: tuple[float, ...] = tuple(float(a) for a in range(0, 85, 5))
    renders: int = 4
    render_size: int = 64
    render_spp: int = 16

    @classmethod
    def parse(cls, d: dict) -> AppearanceSettings:
        angles = d.get("angles_deg", list(cls().angles_deg))
        if not isinstance(angles, list) or not angles:
            raise ValueError(f"[appearance] angles_deg must be a non-empty list, got {angles!r}")
        angles = tuple(_real("appearance", "angles_deg", a, 0.0, 89.0) for a in angles)
        values = _settings(cls, "appearance", {k: v for k, v in d.items() if k != "angles_deg"}, {
            "draws": (2, 100000), "renders": (0, 64), "render_size": (8, 1024), "render_spp": (1, 65536)})
        return cls(angles_deg=angles, **values)


@dataclass(frozen=True)
class FitConfig:
    priors: dict[str, Prior]
    fixed: dict[str, float]
    sampler: SamplerSettings = SamplerSettings()
    model: ModelSettings = ModelSettings()
    appearance: AppearanceSettings = AppearanceSettings()
    source: str = ""

    @property
    def free(self) -> tuple[str, ...]:
        """Names of the sampled parameters, in the canonical order."""
        return tuple(n for n in P.ALL_NAMES if n in self.priors)

    @classmethod
    def parse(cls, d: dict, source: str = "") -> FitConfig:
        _check_keys("top level", d, {"parameters": 0, "sampler": 0, "model": 0, "appearance": 0})
        params = d.get("parameters", {})
        if not isinstance(params, dict):
            raise ValueError("[parameters] must be a table")
        priors, fixed = {}, {}
        for name, spec in params.items():
            P.parameter(name)  # ValueError for an unknown name
            if isinstance(spec, dict) and set(spec) == {"fixed"}:
                spec = spec["fixed"]
            if isinstance(spec, dict):
                prior = Prior.make(name, spec)  # support beyond the model's domain: -inf there
                priors[name] = prior
            else:
                value = _real("parameters", name, spec, -math.inf)
                if not P.in_domain(name, value):
                    p = P.parameter(name)
                    raise ValueError(f"parameter {name!r}: fixed value {value:g} is outside [{p.lo:g}, {p.hi:g}]")
                fixed[name] = value
        if not priors:
            raise ValueError("[parameters]: no free parameter (give at least one a prior)")
        for p in P.ALL.values():
            if p.name not in priors and p.name not in fixed:
                fixed[p.name] = p.default
        sampler = SamplerSettings.parse(d.get("sampler", {}))
        if sampler.walkers < 2 * len(priors):
            raise ValueError(f"[sampler] walkers must be at least twice the number of free parameters "
                             f"({2 * len(priors)}), got {sampler.walkers}")
        return cls(priors, fixed, sampler, ModelSettings.parse(d.get("model", {})),
                   AppearanceSettings.parse(d.get("appearance", {})), source)

    @classmethod
    def load(cls, path: str | os.PathLike) -> FitConfig:
        path = os.fspath(path)
        try:
            return cls.parse(load_toml(path), path)
        except ValueError as e:
            msg = str(e)
            raise ValueError(msg if msg.startswith(path) else f"{path}: {msg}") from None


@dataclass(frozen=True)
class Measurement:
    geometry: str
    angles: tuple[tuple[float, float], ...]   # (in, out); out is NaN unless diffuse
    wavelengths_nm: np.ndarray


@dataclass(frozen=True)
class SimulationConfig:
    truth: dict[str, float]
    relative_noise: float
    absolute_noise: float
    seed: int
    measurements: tuple[Measurement, ...]
    model: ModelSettings = field(default_factory=ModelSettings)

    @classmethod
    def parse(cls, d: dict) -> SimulationConfig:
        from bsdflab.fit.data import GEOMETRIES

        _check_keys("top level", d, {"truth": 0, "noise": 0, "measurement": 0, "model": 0})
        truth = {p.name: p.default for p in P.ALL.values()}
        for name, value in d.get("truth", {}).items():
            P.parameter(name)
            v = _real("truth", name, value, -math.inf)
            if not P.in_domain(name, v):
                raise ValueError(f"[truth] {name} = {v:g} is outside the model's domain")
            truth[name] = v
        noise = d.get("noise", {})
        _check_keys("noise", noise, {"relative": 0, "absolute": 0, "seed": 0})
        rel = _real("noise", "relative", noise.get("relative", 0.02), 0.0)
        ab = _real("noise", "absolute", noise.get("absolute", 0.001), 0.0)
        if rel == 0 and ab == 0:
            raise ValueError("[noise] relative and absolute cannot both be 0 (sigma must be > 0)")
        seed = _integer("noise", "seed", noise.get("seed", 0), 0, 2**63 - 1)
        items = d.get("measurement", [])
        if not isinstance(items, list) or not items:
            raise ValueError("need at least one [[measurement]] table")
        ms = []
        for i, m in enumerate(items):
            sec = f"measurement {i + 1}"
            _check_keys(sec, m, {"geometry": 0, "angles_deg": 0, "angle_pairs_deg": 0, "wavelengths_nm": 0})
            g = m.get("geometry")
            if g not in GEOMETRIES:
                raise ValueError(f"[{sec}] geometry must be one of {', '.join(GEOMETRIES)}, got {g!r}")
            if g == "diffuse":
                pairs = m.get("angle_pairs_deg")
                if (not isinstance(pairs, list) or not pairs
                        or not all(isinstance(p, list) and len(p) == 2 for p in pairs)):
                    raise ValueError(f"[{sec}] a diffuse measurement needs angle_pairs_deg = [[in, out], ...]")
                angles = tuple((_real(sec, "angle_pairs_deg", a, 0, 89.9),
                                _real(sec, "angle_pairs_deg", b, -89.9, 89.9))
                               for a, b in pairs)
            else:
                raw = m.get("angles_deg")
                if not isinstance(raw, list) or not raw:
                    raise ValueError(f"[{sec}] needs angles_deg = [...]")
                angles = tuple((_real(sec, "angles_deg", a, 0, 89.9), math.nan) for a in raw)
            wl = m.get("wavelengths_nm")
            if isinstance(wl, dict):
                _check_keys(f"{sec}.wavelengths_nm", wl, {"start": 0, "stop": 0, "step": 0})
                start, stop = (_real(sec, "start", wl.get("start"), 0, lo_open=True),
                               _real(sec, "stop", wl.get("stop"), 0))
                step = _real(sec, "step", wl.get("step"), 0, lo_open=True)
                grid = start + step * np.arange(int(round((stop - start) / step)) + 1)
            elif isinstance(wl, list) and wl:
                grid = np.array([_real(sec, "wavelengths_nm", w, 0, lo_open=True) for w in wl])
            else:
                raise ValueError(f"[{sec}] wavelengths_nm must be {{start, stop, step}} or a list")
            ms.append(Measurement(g, angles, grid))
        return cls(truth, rel, ab, seed, tuple(ms), ModelSettings.parse(d.get("model", {})))

    @classmethod
    def load(cls, path: str | os.PathLike) -> SimulationConfig:
        path = os.fspath(path)
        try:
            return cls.parse(load_toml(path))
        except ValueError as e:
            msg = str(e)
            raise ValueError(msg if msg.startswith(path) else f"{path}: {msg}") from None
