"""/v1/presets and /v1/scenes: what can be asked for, with its parameters."""
from __future__ import annotations

import inspect

from fastapi import APIRouter

from bsdflab.presets import PRESETS
from bsdflab.requests import keyword_defaults, preset_parameters
from bsdflab.scenes import SCENES
from bsdflab.service.schemas import PresetInfo, SceneInfo

router = APIRouter(prefix="/v1", tags=["catalogue"])


def _first_line(obj) -> str:
    return ((inspect.getdoc(obj) or "").strip().splitlines() or [""])[0]


@router.get("/presets", response_model=list[PresetInfo], summary="The preset materials")
def presets() -> list[PresetInfo]:
    """Each preset with its keyword parameters (overridable in a request's ``overrides``)
    and its model in the ``to_dict`` form."""
    return [PresetInfo(name=name, description=_first_line(make), parameters=preset_parameters(name),
                       model=make().to_dict()) for name, make in PRESETS.items()]


@router.get("/scenes", response_model=list[SceneInfo], summary="The scenes a render can ask for")
def scenes() -> list[SceneInfo]:
    """Each scene with its keyword options and their defaults (``width`` and ``height`` are
    a render request's own fields)."""
    return [SceneInfo(name=name, description=_first_line(make), parameters=keyword_defaults(make))
            for name, make in SCENES.items()]
