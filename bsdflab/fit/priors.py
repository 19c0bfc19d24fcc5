"""Prior distributions of the fit's parameters, on top of scipy.stats.

TOML form (one inline table per parameter, see docs/fit_data.md):
    uniform      {prior = "uniform", low, high}
    normal       {prior = "normal", mean, sd}
    lognormal    {prior = "lognormal", median, sigma}       (sigma of log x)
    truncnormal  {prior = "truncnormal", mean, sd, low, high}
A bare number, or {fixed = x}, fixes the parameter.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import stats

_HALF_LOG_2PI = 0.5 * float(np.log(2.0 * np.pi))
KINDS = {"uniform": ("low", "high"), "normal": ("mean", "sd"), "lognormal": ("median", "sigma"),
         "truncnormal": ("mean", "sd", "low", "high")}


@dataclass(frozen=True)
class Prior:
    kind: str
    args: tuple[tuple[str, float], ...]

    @classmethod
    def make(cls, name: str, spec: dict) -> Prior:
        kind = spec.get("prior")
        if kind not in KINDS:
            raise ValueError(f"parameter {name!r}: prior must be one of {', '.join(KINDS)}, got {kind!r}")
        keys = KINDS[kind]
        extra = set(spec) - {"prior", *keys}
        missing = [k for k in keys if k not in spec]
        if missing or extra:
            raise ValueError(f"parameter {name!r}: a {kind} prior takes {', '.join(keys)}; "
                             f"missing {missing or 'none'}, unknown {sorted(extra) or 'none'}")
        args = {}
        for k in keys:
            v = spec[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"parameter {name!r}: {k} must be a finite number, got {v!r}")
            args[k] = float(v)
        for k in ("sd", "sigma"):
            if k in args and args[k] <= 0:
                raise ValueError(f"parameter {name!r}: {k} must be > 0, got {args[k]:g}")
        if "low" in args and not args["low"] < args["high"]:
            raise ValueError(f"parameter {name!r}: low must be < high, got {args['low']:g}, {args['high']:g}")
        if kind == "lognormal" and args["median"] <= 0:
            raise ValueError(f"parameter {name!r}: median must be > 0, got {args['median']:g}")
        return cls(kind, tuple(args.items()))

    @cached_property
    def dist(self):
        a = dict(self.args)
        if self.kind == "uniform":
            return stats.uniform(loc=a["low"], scale=a["high"] - a["low"])
        if self.kind == "normal":
            return stats.norm(loc=a["mean"], scale=a["sd"])
        if self.kind == "lognormal":
            return stats.lognorm(s=a["sigma"], scale=a["median"])
        return stats.truncnorm((a["low"] - a["mean"]) / a["sd"], (a["high"] - a["mean"]) / a["sd"],
                               loc=a["mean"], scale=a["sd"])

    def logpdf(self, x) -> np.ndarray:
        """log density (-inf outside the support). Written out in numpy because scipy's
        generic logpdf costs ~50x more per call, and emcee calls it every half-step;
        tests/test_fit_inputs.py checks it against scipy.stats."""
        x = np.asarray(x, dtype=float)
        a = dict(self.args)
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.kind == "uniform":
                inside = (x >= a["low"]) & (x <= a["high"])
                return np.where(inside, -np.log(a["high"] - a["low"]), -np.inf)
            if self.kind == "lognormal":
                z = (np.log(x) - np.log(a["median"])) / a["sigma"]
                out = -0.5 * z * z - np.log(a["sigma"] * x) - _HALF_LOG_2PI
                return np.where(x > 0, out, -np.inf)
            z = (x - a["mean"]) / a["sd"]
            out = -0.5 * z * z - np.log(a["sd"]) - _HALF_LOG_2PI
            if self.kind == "normal":
                return out
            inside = (x >= a["low"]) & (x <= a["high"])
            return np.where(inside, out - self._log_mass, -np.inf)

    @cached_property
    def _log_mass(self) -> float:
        """log of the normal's probability inside [low, high] (truncnormal's normaliser)."""
        a = dict(self.args)
        lo, hi = (a["low"] - a["mean"]) / a["sd"], (a["high"] - a["mean"]) / a["sd"]
        return float(np.log(stats.norm.cdf(hi) - stats.norm.cdf(lo)))

    def ppf(self, u) -> np.ndarray:
        return self.dist.ppf(u)

    def support(self) -> tuple[float, float]:
        lo, hi = self.dist.support()
        return float(lo), float(hi)

    def describe(self) -> str:
        return f"{self.kind}(" + ", ".join(f"{k}={v:g}" for k, v in self.args) + ")"

    def to_dict(self) -> dict:
        return {"prior": self.kind, **dict(self.args)}
