"""A scene's ``material`` option as a BSDF dict: the object scenes (sphere, torus) and the
snake take a name ("table", "direct", for the snake a preset name) or any material of
one's own, as a dict:

- a BSDF dict (``BSDF.to_dict`` form, e.g. ``{"type": "diffuse", "reflectance": 0.5}``),
  evaluated directly at every hit;
- a preset and its keyword overrides, ``{"preset": "xenopeltis", "overrides": {...}}``
  (overrides optional), evaluated directly;
- ``{"type": "tabulated", "model": <either of the above>, ...}``: the model's table (the
  table request's fields, bsdflab.tables.request: ``grid`` (default: the scenes' table
  grid), ``rel_error`` (default 0.02), ``method`` (default "auto": adding-doubling
  wherever it covers the model), ...), made once and then read from the table cache;
- a stored file, ``{"type": "table" | "measured" | "merl", ...}`` (over HTTP: named by
  its hash, bsdflab.service.artefact_refs).
"""

from __future__ import annotations

from typing import Any

from bsdflab.presets import FILM_THICKNESS_NM, preset
from bsdflab.tables.data import TableGrid
from bsdflab.tables.table_bsdf import default_film_thickness
from bsdflab.util import args as check

TABULATED = "tabulated"
PRESET_KEYS = frozenset({"preset", "overrides"})
TABLE_REL_ERROR = 0.02  # the scenes' own tables' target (bsdflab.scenes.snake.tabulated)
STORED = ("table", "measured", "merl")  # files: not loaded to choose a grid


def model_dict(spec: Any, where: str = "material") -> dict[str, Any]:
    """A model dict from a BSDF dict or a ``{"preset": ..., "overrides": ...}`` form."""
    if not isinstance(spec, dict):
        raise ValueError(f"{where} must be a dict (a BSDF dict, or a preset and overrides), got {check.brief(spec)}")
    if "preset" in spec:
        unknown = sorted(map(str, set(spec) - PRESET_KEYS))
        if unknown:
            raise ValueError(f"{where}: a preset form takes 'preset' and 'overrides' only, not {', '.join(unknown)}")
        overrides = spec.get("overrides") or {}
        if not isinstance(overrides, dict):
            raise ValueError(f"{where}.overrides must be a dict of the preset's keyword parameters")
        try:
            return preset(spec["preset"], **overrides).to_dict()
        except (TypeError, ValueError) as e:
            raise ValueError(f"{where}: {e}") from None
    if not isinstance(spec.get("type"), str):
        raise ValueError(f"{where} needs a 'type' (a BSDF dict) or a 'preset'")
    return dict(spec)


def _stored(value: Any) -> bool:
    if isinstance(value, dict):
        return value.get("type") in STORED or any(_stored(v) for v in value.values())
    return isinstance(value, list) and any(_stored(v) for v in value)


def table_grid(thickness_jitter: float, film_nm: float = FILM_THICKNESS_NM) -> dict:
    """The scenes' modest table grid, its thickness nodes spanning the scales' film-thickness
    jitter (none without jitter)."""
    nodes = (film_nm * (1 - thickness_jitter), film_nm, film_nm * (1 + thickness_jitter))
    return TableGrid(8, 16, 9, nodes if thickness_jitter > 0 else ()).to_dict()


def default_grid(model: dict[str, Any], jitter: float) -> dict[str, Any]:
    """The scenes' table grid with thickness nodes spanning the scales' jitter about the
    model's own film thickness (none without a film, or for a stored file)."""
    film = -1.0 if _stored(model) else default_film_thickness(model)
    return table_grid(jitter, film) if film > 0 else table_grid(0.0)


def custom_bsdf(material: Any, jitter: float) -> dict[str, Any] | None:
    """The BSDF dict of a dict ``material`` (None for a name: the scene's own choices); a
    tabulated one without a ``grid`` gets ``default_grid`` (``jitter``: the scales' film
    thickness jitter). ValueError naming the field."""
    if isinstance(material, str):
        return None
    if not isinstance(material, dict):
        raise ValueError(
            f"material must be a name or a dict (a BSDF dict, a preset and overrides, or "
            f'{{"type": "tabulated", "model": ...}}), got {check.brief(material)}'
        )
    if material.get("type") != TABULATED:
        return model_dict(material)
    if "model" not in material:
        raise ValueError('material: a tabulated material needs "model" (a BSDF dict, or a preset and overrides)')
    model = model_dict(material["model"], "material.model")
    grid = material["grid"] if "grid" in material else default_grid(model, jitter)
    return {"rel_error": TABLE_REL_ERROR, **material, "grid": grid, "model": model}
