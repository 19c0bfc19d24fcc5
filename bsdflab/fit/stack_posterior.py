"""The log posterior of a structure fit: one structure, one or more datasets (co-refinement,
refnx's GlobalObjective practice), each seen through its own instrument.

    log p = sum_j log prior_j + sum_datasets sum_rows log N(y_i | m_i(theta), (s sigma_i)^2)

The structure's parameters and noise_scale s are shared; every dataset has its own
instrument parameters (``<dataset>.scale``, ...; per-series scales ``scale_<angle>``).
Same interface as bsdflab.fit.posterior.LogPosterior, so bsdflab.fit.sampling runs it.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from bsdflab.fit import parameters as P
from bsdflab.fit.config import SamplerSettings
from bsdflab.fit.data import Dataset
from bsdflab.fit.instrument import BY_NAME as INSTRUMENT
from bsdflab.fit.posterior import GaussianPosterior
from bsdflab.fit.priors import Prior
from bsdflab.fit.stack_config import StackConfig
from bsdflab.fit.stack_forward import StackForward
from bsdflab.fit.stack_material import stack_material_dict, stack_material_note

_LOG_2PI = float(np.log(2.0 * np.pi))


def series_name(angle_deg: float) -> str:
    return "scale_" + f"{angle_deg:g}".replace(".", "p").replace("-", "m")


def series_scales(dataset: Dataset) -> tuple[list[str], np.ndarray]:
    """``scale_per_series``'s parameter names (without the dataset prefix) and each row's
    index into them: one per named series (``Dataset.series``, as ``bsdflab fit import``
    writes it: one per file, sample or instrument) when the rows name any, else one per
    incidence angle (``scale_<angle>``)."""
    if any(dataset.series):
        keys, index = np.unique(dataset.series.astype(str), return_inverse=True)
        names = ["scale_" + (re.sub(r"[^a-z0-9_]+", "_", k.lower()).strip("_") or "unnamed") for k in keys]
        if len(set(names)) < len(names):
            raise ValueError(f"scale_per_series: the series names {', '.join(map(repr, keys))} do not give "
                             "distinct parameter names (scale_<series> in lower-case letters, digits and _)")
        return names, index
    angles, index = np.unique(dataset.angle_deg, return_inverse=True)
    return [series_name(a) for a in angles], index


@dataclass(frozen=True)
class BoundConfig:
    """A StackConfig bound to its datasets: every parameter name, prior and fixed value."""

    names: tuple[str, ...]
    domains: dict[str, P.Parameter]
    priors: dict[str, Prior]
    fixed: dict[str, float]
    sampler: SamplerSettings
    stack: StackConfig

    @property
    def free(self) -> tuple[str, ...]:
        return tuple(n for n in self.names if n in self.priors)


def concatenate(datasets, names=None) -> Dataset:
    """All rows in one Dataset; each row's series is ``<dataset name>/<its series>`` (either
    part left out where empty), so checks and figures tell the datasets apart."""
    names = names or [""] * len(datasets)

    def cat(key):
        return np.concatenate([getattr(d, key) for d in datasets])
    series = np.concatenate([np.array(["/".join(p for p in (name, str(s)) if p) for s in d.series], dtype=object)
                             for name, d in zip(names, datasets)])
    return Dataset(cat("geometry"), cat("angle_deg"), cat("angle_out_deg"), cat("wavelength_nm"),
                   cat("reflectance"), cat("sigma"), [c for d in datasets for c in d.comments], cat("phi_deg"), series)


def bind(post, config, datasets, modelled) -> tuple[dict, dict]:
    """Binds a structure posterior's parameters: the structure's, noise_scale and each
    dataset's instrument parameters in ``modelled`` (per series where asked), in that order;
    sets ``post.config``, ``free``, ``col`` and the domain arrays. Returns (domains, priors)."""
    domains = {p.name: p for p in (*config.structure.parameters(), P.NOISE)}
    priors, fixed = dict(config.priors), dict(config.fixed)
    post._series = [series_scales(d) if spec.instrument.scale_per_series else None
                    for spec, d in zip(config.datasets, datasets)]
    for spec, per in zip(config.datasets, post._series):
        inst = spec.instrument
        for name in modelled:
            names = ([spec.prefix(n) for n in per[0]] if name == "scale" and per else [spec.prefix(name)])
            for full in names:
                domains[full] = INSTRUMENT[name]
                if name in inst.priors:
                    priors[full] = inst.priors[name]
                else:
                    fixed[full] = inst.fixed[name]
    names = tuple(domains)
    post.config = BoundConfig(names, domains, priors, fixed, config.sampler, config)
    post.free = post.config.free
    if config.sampler.walkers < 2 * len(post.free):
        raise ValueError(f"[sampler] walkers must be at least twice the number of free parameters "
                         f"({2 * len(post.free)}), got {config.sampler.walkers}")
    post.col = {n: i for i, n in enumerate(names)}
    post._noise_col = post.col["noise_scale"]
    post._base = np.array([fixed.get(n, np.nan) for n in names])
    post._free_cols = np.array([post.col[n] for n in post.free], dtype=int)
    post._lo = np.array([domains[n].lo for n in names])
    post._hi = np.array([domains[n].hi for n in names])
    post._lo_open = np.array([domains[n].lo_open for n in names])
    return domains, priors


class StackPosterior(GaussianPosterior):
    ROW_KEYS = ("geometry", "angle_deg", "wavelength_nm")  # specular rows

    def __init__(self, datasets, config: StackConfig):
        """``datasets``: one Dataset per [[dataset]] entry, in the config's order."""
        datasets = list(datasets)
        if len(datasets) != len(config.datasets):
            raise ValueError(f"the config names {len(config.datasets)} dataset(s), got {len(datasets)}")
        self.datasets, self.stack = datasets, config
        m = config.model
        self.models = [StackForward(d, config.structure, m.bandwidth_nodes, m.cone_nodes, m.cone_azimuths,
                                    m.thickness_nodes)
                       for d in datasets]
        bind(self, config, datasets, tuple(INSTRUMENT))
        self.dataset = concatenate(datasets, [spec.name for spec in config.datasets])
        self.evaluations = 0

    def named(self, x) -> dict[str, np.ndarray]:
        full = self.full(x)
        return {n: full[:, i] for i, n in enumerate(self.config.names)}

    def _model_values(self, full: np.ndarray) -> np.ndarray:
        inside = np.all(np.isfinite(full) & np.where(self._lo_open, full > self._lo, full >= self._lo)
                        & (full <= self._hi), axis=1)
        out = np.full((len(full), len(self.dataset)), np.nan)
        if not np.any(inside):
            return out
        f = full[inside]

        def value(name):
            return f[:, self.col[name]]
        parts = []
        for spec, model, per in zip(self.stack.datasets, self.models, self._series):
            def inst(name, spec=spec):
                return value(spec.prefix(name))
            if per:
                scale = np.column_stack([value(spec.prefix(n)) for n in per[0]])[:, per[1]]
            else:
                scale = inst("scale")
            parts.append(model.evaluate(value, scale, inst("background"), inst("angle_offset_deg"),
                                        inst("acceptance_deg"), inst("bandwidth_nm")))
        out[inside] = np.concatenate(parts, axis=1)
        return out

    def _values(self, x) -> dict[str, float]:
        return {n: float(v[0]) for n, v in self.named(np.atleast_2d(x)).items()}

    def material_dict(self, x) -> dict:
        """The renderable model dict of one free parameter vector (bsdflab.fit.stack_material)."""
        return stack_material_dict(self.stack.structure, self._values(x))

    def material_note(self, x) -> str:
        """What that dict carries of the fit and what not (summary.json)."""
        return stack_material_note(self.stack.structure, self._values(x))
