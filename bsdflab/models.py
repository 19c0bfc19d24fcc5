"""A model from its request form, as the CLI, the HTTP API and job requests carry it.

Either ``{"model": <BSDF.to_dict() form>}`` or ``{"preset": name, "overrides": {...}}``,
where the overrides are the preset's keyword parameters (``bsdflab.presets``).
"""
from __future__ import annotations

import inspect
from typing import Any

from .bsdfs.base import BSDF, from_dict
from .presets import PRESETS, preset


def model_from_spec(spec: dict[str, Any]) -> BSDF:
    """The BSDF a request describes; ValueError naming what is wrong otherwise."""
    if not isinstance(spec, dict):
        raise ValueError(f"a model spec must be a dict, got {type(spec).__name__}")
    has_model, has_preset = spec.get("model") is not None, spec.get("preset") is not None
    if has_model == has_preset:
        raise ValueError("give exactly one of 'model' (a BSDF dict) or 'preset' (a preset name)")
    if has_model:
        if spec.get("overrides"):
            raise ValueError("'overrides' apply to a preset, not to a model dict")
        return from_dict(spec["model"])
    overrides = spec.get("overrides") or {}
    if not isinstance(overrides, dict):
        raise ValueError("'overrides' must be a dict of the preset's keyword parameters")
    return preset(spec["preset"], **overrides)


def keyword_defaults(function) -> dict[str, Any]:
    """A function's keyword parameters with their defaults (tuples as lists: JSON values)."""
    params = inspect.signature(function).parameters.values()
    return {p.name: list(p.default) if isinstance(p.default, tuple) else p.default for p in params
            if p.default is not inspect.Parameter.empty}


def preset_parameters(name: str) -> dict[str, Any]:
    """The keyword parameters of preset ``name`` with their defaults."""
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; known presets: {', '.join(PRESETS)}")
    return keyword_defaults(PRESETS[name])
