"""A model from its request form, as the CLI, the HTTP API and job requests carry it.

Either ``{"model": <BSDF.to_dict() form>}`` or ``{"preset": name, "overrides": {...}}``,
where the overrides are the preset's keyword parameters (``bsdflab.presets``).
"""
from __future__ import annotations

import collections
import inspect
import json
import os
import threading
from typing import Any

from bsdflab.bsdfs.base import BSDF, from_dict
from bsdflab.presets import PRESETS, preset


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


class ModelCache:
    """The last ``size`` models built by `model_from_spec`, by their spec: building a
    spectral model's core objects costs far more than a small query (a server keeps one).
    At most ``max_bytes`` of models by `model_bytes` (a measured file's model is tens of MB;
    one larger than the bound is built and not kept). BSDF objects are safe to share
    between threads (the core is thread-safe)."""

    def __init__(self, size: int = 32, max_bytes: int | None = None):
        self.size, self.max_bytes = size, max_bytes
        self._models: collections.OrderedDict[str, tuple[BSDF, int]] = collections.OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()

    @property
    def bytes(self) -> int:
        return self._bytes

    def __len__(self) -> int:
        return len(self._models)

    def get(self, spec: dict[str, Any]) -> BSDF:
        try:
            key = json.dumps(spec, sort_keys=True, allow_nan=False)
        except (TypeError, ValueError) as e:
            raise ValueError(f"a model spec must be plain JSON: {e}") from None
        with self._lock:
            if key in self._models:
                self._models.move_to_end(key)
                return self._models[key][0]
        model = model_from_spec(spec)
        size = model_bytes(model)
        if self.max_bytes is not None and size > self.max_bytes:
            return model
        with self._lock:
            if key not in self._models:
                self._models[key] = (model, size)
                self._bytes += size
            while len(self._models) > self.size or (self.max_bytes is not None and self._bytes > self.max_bytes):
                self._bytes -= self._models.popitem(last=False)[1][1]
        return model


SMALL_MODEL_BYTES = 64 << 10   # a parametric model and its core objects


def model_bytes(model: BSDF) -> int:
    """About the memory a built model holds: twice its file for a model that reads one
    (the values as read and the core's copy), else a small constant."""
    path = getattr(model, "path", None) if getattr(model, "reads_path", False) else None
    if isinstance(path, str) and os.path.isfile(path):
        return 2 * os.path.getsize(path) + SMALL_MODEL_BYTES
    return SMALL_MODEL_BYTES


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
