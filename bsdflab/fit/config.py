"""Fit and simulation settings from TOML files (stdlib ``tomllib``; docs/fit_data.md).

fit.toml
    [parameters]   one entry per parameter: a prior (bsdflab.fit.priors) or a fixed value;
                   parameters left out are fixed at their defaults (bsdflab.fit.parameters)
    [sampler]      kind (emcee | nested); emcee: walkers, max_steps (the step cap),
                   tau_multiple (run until N > tau_multiple * tau), check_every, map_starts;
                   nested: live_points, dlogz; both: seed
    [model]        kind (smooth | full), film (single | none | stack), distribution,
                   platelets; thickness_nodes, angle_nodes (the smooth model's quadrature
                   orders); nodes, orders (the full model's adding-doubling solver)
    [appearance]   draws, angles_deg, renders, render_size, render_spp
truth.toml (``bsdflab fit simulate``)
    [truth]        parameter values (missing ones: defaults)
    [noise]        relative, absolute, seed: sigma_i = sqrt(absolute^2 + (relative y_i)^2)
    [[measurement]] geometry, angles_deg (or angle_pairs_deg [in, out] for diffuse,
                   angle_triples_deg [in, out, phi] for brdf), wavelengths_nm
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


def _table(section: str, d) -> dict:
    """``d`` itself when it is a TOML table (before: a number or list there raised an
    AttributeError, a 500 over HTTP)."""
    if not isinstance(d, dict):
        raise ValueError(f"[{section}] must be a table, got {type(d).__name__}")
    return d


def _settings(cls, section: str, d: dict, ranges: dict) -> dict:
    """Values of the keys in ``ranges`` ({key: (lo, hi)}; float bounds mean a real number)
    from table ``d``, each defaulting to the dataclass ``cls``'s default."""
    _check_keys(section, d, cls.__dataclass_fields__)
    base, out = cls(), {}
    for key, (lo, hi) in ranges.items():
        v = d.get(key, getattr(base, key))
        out[key] = _real(section, key, v, lo, hi) if isinstance(lo, float) else _integer(section, key, v, lo, hi)
    return out


KINDS = ("smooth", "full")
FILMS = ("single", "none", "stack")
DISTRIBUTIONS = ("ggx", "beckmann")


@dataclass(frozen=True)
class ModelSettings:
    """The forward model: ``kind`` smooth (the closed-form C++ model: smooth top, non-
    scattering slab) or full (the rendered ``Layered`` model solved by adding-doubling:
    rough top of microfacet ``distribution``, scattering Henyey-Greenstein slab, top film
    ``film`` = one film, none, or a stack of ``platelets`` platelets); quadrature orders
    of the smooth model; the solver's ``nodes`` and ``orders`` (0: automatic); the full
    model's Chebyshev emulator: ``emulator_nodes`` per free parameter (0: a direct solve per
    evaluation) and ``emulator_checks`` direct solves that measure its error."""

    kind: str = "smooth"
    film: str = "single"
    distribution: str = "ggx"
    platelets: int = 5
    thickness_nodes: int = 24
    angle_nodes: int = 32
    nodes: int = 16
    orders: int = 0
    emulator_nodes: int = 5
    emulator_checks: int = 2

    @classmethod
    def parse(cls, d: dict) -> ModelSettings:
        d = _table("model", d)
        words = {}
        for key, known in (("kind", KINDS), ("film", FILMS), ("distribution", DISTRIBUTIONS)):
            v = d.get(key, getattr(cls(), key))
            if v not in known:
                raise ValueError(f"[model] {key} must be one of {', '.join(known)}, got {v!r}")
            words[key] = v
        numbers = {k: v for k, v in d.items() if k not in words}
        s = cls(**words, **_settings(cls, "model", numbers, {
            "thickness_nodes": (1, 200), "angle_nodes": (2, 1000), "platelets": (1, 16),
            "nodes": (4, 256), "orders": (0, 4096), "emulator_nodes": (0, 64), "emulator_checks": (0, 1000)}))
        if s.kind == "smooth" and s.film != "single":
            raise ValueError(f"[model] film = {s.film!r} needs kind = 'full' (the smooth model has one "
                             "film; fix film_thickness_nm = 0 for none)")
        return s

    def names(self) -> tuple[str, ...]:
        """The parameters this model uses (canonical order); the others may not be given."""
        if self.kind == "smooth":
            return (*P.FORWARD_NAMES, P.NOISE.name)
        film = {"single": ("film_thickness_nm", "film_ior", "film_cauchy_b"), "none": (),
                "stack": ("film_ior", "film_cauchy_b", "platelet_nm", "gap_nm", "gap_ior")}[self.film]
        unused = {"film_thickness_spread_nm", "film_thickness_nm", "film_ior", "film_cauchy_b",
                  "platelet_nm", "gap_nm", "gap_ior"} - set(film)
        return tuple(n for n in P.ALL_NAMES if n not in unused)

    def fixed_implied(self) -> dict[str, float]:
        """Values the model implies and nobody may change (the smooth model: a smooth top and
        a non-scattering slab)."""
        return dict(P.SMOOTH_VALUES) if self.kind == "smooth" else {}


SAMPLERS = ("emcee", "nested")


@dataclass(frozen=True)
class SamplerSettings:
    """``kind`` emcee (MAP starts, then the ensemble with the autocorrelation stop) or nested
    (dynesty, bsdflab.fit.nested: every mode and the evidence; ``live_points``, ``dlogz``)."""

    walkers: int = 32
    max_steps: int = 20000
    tau_multiple: float = 50.0
    check_every: int = 200
    seed: int = 0
    map_starts: int = 8
    kind: str = "emcee"
    live_points: int = 200
    dlogz: float = 0.1

    @classmethod
    def parse(cls, d: dict) -> SamplerSettings:
        d = _table("sampler", d)
        kind = d.get("kind", "emcee")
        if kind not in SAMPLERS:
            raise ValueError(f"[sampler] kind must be one of {', '.join(SAMPLERS)}, got {kind!r}")
        s = cls(kind=kind, **_settings(cls, "sampler", {k: v for k, v in d.items() if k != "kind"}, {
            "walkers": (4, 10000), "max_steps": (10, 10_000_000), "tau_multiple": (1.0, math.inf),
            "check_every": (10, 1_000_000), "seed": (0, 2**63 - 1), "map_starts": (1, 1000),
            "live_points": (4, 1_000_000), "dlogz": (1e-6, math.inf)}))
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
        d = _table("appearance", d)
        angles = d.get("angles_deg", list(cls().angles_deg))
        if not isinstance(angles, list) or not angles:
            raise ValueError(f"[appearance] angles_deg must be a non-empty list, got {angles!r}")
        angles = tuple(_real("appearance", "angles_deg", a, 0.0, 89.0) for a in angles)
        values = _settings(cls, "appearance", {k: v for k, v in d.items() if k != "angles_deg"}, {
            "draws": (2, 100000), "renders": (0, 64), "render_size": (8, 1024), "render_spp": (1, 65536)})
        return cls(angles_deg=angles, **values)


@dataclass(frozen=True)
class OutputSettings:
    """What a study writes besides its numbers: ``figures`` false leaves out the PNGs (corner,
    predictive, residuals, trace, appearance, renders), seconds of matplotlib per study that a
    batch of fits read only through summary.json and the tables does not need."""

    figures: bool = True

    @classmethod
    def parse(cls, d: dict) -> OutputSettings:
        d = _table("output", d)
        _check_keys("output", d, {"figures": 0})
        figures = d.get("figures", cls.figures)
        if not isinstance(figures, bool):
            raise ValueError(f"[output] figures must be true or false, got {figures!r}")
        return cls(figures)


@dataclass(frozen=True)
class FitConfig:
    priors: dict[str, Prior]
    fixed: dict[str, float]
    sampler: SamplerSettings = SamplerSettings()
    model: ModelSettings = ModelSettings()
    appearance: AppearanceSettings = AppearanceSettings()
    source: str = ""
    output: OutputSettings = OutputSettings()

    @property
    def free(self) -> tuple[str, ...]:
        """Names of the sampled parameters, in the canonical order."""
        return tuple(n for n in P.ALL_NAMES if n in self.priors)

    @classmethod
    def parse(cls, d: dict, source: str = "") -> FitConfig:
        _check_keys("top level", d, {"parameters": 0, "sampler": 0, "model": 0, "appearance": 0, "output": 0})
        params = d.get("parameters", {})
        if not isinstance(params, dict):
            raise ValueError("[parameters] must be a table")
        model = ModelSettings.parse(d.get("model", {}))
        used = model.names()
        priors, fixed = {}, {}
        params = {P.canonical(k, "[parameters] "): v for k, v in params.items()}
        for name, spec in params.items():
            P.parameter(name)  # ValueError for an unknown name
            if name not in used:
                raise ValueError(f"parameter {name!r} is not part of the {model.kind} model"
                                 + (f" with film = {model.film!r}" if model.kind == "full" else "")
                                 + f"; its parameters: {', '.join(used)}")
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
        for name in used:
            if name not in priors and name not in fixed:
                fixed[name] = P.parameter(name).default
        fixed.update(model.fixed_implied())
        sampler = SamplerSettings.parse(d.get("sampler", {}))
        if sampler.walkers < 2 * len(priors):
            raise ValueError(f"[sampler] walkers must be at least twice the number of free parameters "
                             f"({2 * len(priors)}), got {sampler.walkers}")
        return cls(priors, fixed, sampler, model, AppearanceSettings.parse(d.get("appearance", {})), source,
                   OutputSettings.parse(d.get("output", {})))

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
    angles: tuple[tuple[float, float, float], ...]   # (in, out, phi); out NaN unless diffuse/brdf, phi unless brdf
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
        model = ModelSettings.parse(d.get("model", {}))
        used = model.names()
        truth = {n: P.parameter(n).default for n in used}
        for name, value in {P.canonical(k, "[truth] "): v for k, v in d.get("truth", {}).items()}.items():
            P.parameter(name)
            if name not in used:
                raise ValueError(f"[truth] {name} is not part of the {model.kind} model; its parameters: "
                                 f"{', '.join(used)}")
            v = _real("truth", name, value, -math.inf)
            if not P.in_domain(name, v):
                raise ValueError(f"[truth] {name} = {v:g} is outside the model's domain")
            truth[name] = v
        truth.update(model.fixed_implied())
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
            _check_keys(sec, m, {"geometry": 0, "angles_deg": 0, "angle_pairs_deg": 0, "angle_triples_deg": 0,
                                 "wavelengths_nm": 0})
            g = m.get("geometry")
            if g not in GEOMETRIES:
                raise ValueError(f"[{sec}] geometry must be one of {', '.join(GEOMETRIES)}, got {g!r}")
            if g == "diffuse":
                pairs = m.get("angle_pairs_deg")
                if (not isinstance(pairs, list) or not pairs
                        or not all(isinstance(p, list) and len(p) == 2 for p in pairs)):
                    raise ValueError(f"[{sec}] a diffuse measurement needs angle_pairs_deg = [[in, out], ...]")
                angles = tuple((_real(sec, "angle_pairs_deg", a, 0, 89.9),
                                _real(sec, "angle_pairs_deg", b, -89.9, 89.9), math.nan)
                               for a, b in pairs)
            elif g == "brdf":
                triples = m.get("angle_triples_deg")
                if (not isinstance(triples, list) or not triples
                        or not all(isinstance(p, list) and len(p) == 3 for p in triples)):
                    raise ValueError(f"[{sec}] a brdf measurement needs angle_triples_deg = "
                                     "[[in, out, phi], ...]")
                angles = tuple((_real(sec, "angle_triples_deg", a, 0, 89.9),
                                _real(sec, "angle_triples_deg", b, 0, 89.9),
                                _real(sec, "angle_triples_deg", c, -180.0, 180.0)) for a, b, c in triples)
            else:
                raw = m.get("angles_deg")
                if not isinstance(raw, list) or not raw:
                    raise ValueError(f"[{sec}] needs angles_deg = [...]")
                angles = tuple((_real(sec, "angles_deg", a, 0, 89.9), math.nan, math.nan) for a in raw)
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
        return cls(truth, rel, ab, seed, tuple(ms), model)

    @classmethod
    def load(cls, path: str | os.PathLike) -> SimulationConfig:
        path = os.fspath(path)
        try:
            return cls.parse(load_toml(path))
        except ValueError as e:
            msg = str(e)
            raise ValueError(msg if msg.startswith(path) else f"{path}: {msg}") from None
