"""The procedural scenes by name (the CLI and the HTTP API use these names)."""
from __future__ import annotations

from collections.abc import Callable

from bsdflab.render import Scene
from bsdflab.scenes.appearance_grid import appearance_grid, appearance_grid_cell
from bsdflab.scenes.basic_materials import basic_materials
from bsdflab.scenes.furnace import furnace
from bsdflab.scenes.objects import ablation_row, sphere, torus
from bsdflab.scenes.snake import snake

SCENES: dict[str, Callable[..., Scene]] = {
    "snake": snake,
    "sphere": sphere,
    "torus": torus,
    "appearance-grid": appearance_grid_cell,
    "basic-materials": basic_materials,
    "furnace": furnace,
}

# Sets of scenes rendered together into one labelled contact sheet.
SCENE_SETS: dict[str, Callable[..., list[tuple[str, Scene]]]] = {
    "appearance-grid": appearance_grid,
    "ablation": ablation_row,
}


def scene(name: str, **kwargs) -> Scene:
    """The scene called ``name`` built with ``kwargs`` (width, height and its own options)."""
    if name not in SCENES:
        raise ValueError(f"unknown scene {name!r}; known scenes: {', '.join(SCENES)}")
    try:
        return SCENES[name](**kwargs)
    except TypeError as e:   # an option the scene does not take
        raise ValueError(f"scene {name!r}: {e}") from None


def scene_set(name: str, **kwargs) -> list[tuple[str, Scene]]:
    """The (label, scene) list called ``name`` (see SCENE_SETS)."""
    if name not in SCENE_SETS:
        raise ValueError(f"unknown scene set {name!r}; known sets: {', '.join(SCENE_SETS)}")
    try:
        return SCENE_SETS[name](**kwargs)
    except TypeError as e:
        raise ValueError(f"scene set {name!r}: {e}") from None
