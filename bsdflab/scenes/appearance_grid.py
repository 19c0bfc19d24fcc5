"""The appearance range of thin-film interference (the grid of Padrón-Griffe et al. 2023): film thickness
300 / 600 / 1200 nm x interior index 1.0 / 2.0, on a sphere under the studio lights.

Interpretation. In the paper's layered model the film sits on the skin's interior medium;
"interior index" is that medium's index, i.e. what lies *below* the film (the film's
own index stays the guanine value of the presets, 1.83). Index 1.0 makes the film a
free-standing sheet (both its faces see a lower index, and the two reflections differ in
phase by pi); index 2.0 puts the film's index between its neighbours (no phase flip
between the two reflections), which shifts every interference order: the two rows show
that difference.

Rendering it honestly without six PFMC tables: the film (guanine 1.83, thickness t) lies
on a half-space of index n (1.0 or 2.0) that absorbs everything transmitted into it --
the limit of the snake's dark pigment, which returns only a few per cent. That is a
``roughconductor`` whose substrate index is (eta = n, k = 0) with ``film=``: its Fresnel
term is the exact Airy reflectance of the film stack on a lossless dielectric substrate,
and the conductor form discards the transmitted part, i.e. the black base. Roughness is
the snake's (GGX alpha 0.08); the exterior is index 1.0, so "interior 1.0" really is the
film's own medium on both sides. What this leaves out: the light the diffuse base and
the pigment slab send back (dark, a few per cent), and refraction into a keratin cover.
"""
from __future__ import annotations

from bsdflab.presets import GUANINE_IOR, ROUGHNESS
from bsdflab.render import Material, Scene, Shape
from bsdflab.scenes.snake import ground, ground_material, orbit_camera, sky, soft_box

THICKNESSES_NM = (300.0, 600.0, 1200.0)
INTERIOR_IORS = (1.0, 2.0)


def film_bsdf(thickness_nm: float, interior_ior: float) -> dict:
    return {"type": "roughconductor", "alpha": ROUGHNESS, "eta": float(interior_ior), "k": 0.0, "ext_ior": 1.0,
            "film": [{"material": GUANINE_IOR, "thickness_nm": float(thickness_nm)}]}


def appearance_grid_cell(thickness_nm: float = 600.0, interior_ior: float = 2.0, width: int = 320,
                         height: int = 240, max_depth: int = 8) -> Scene:
    """One cell of the grid: a 10 cm sphere with the film material."""
    centre = [0.0, 10.0, 0.0]
    shapes = (ground(), Shape({"type": "sphere", "center": centre, "radius": 10.0, "subdivisions": 192},
                              material="film", name="sphere"),
              soft_box([-35.0, 70.0, -30.0], centre, 40.0, (14.0, 13.3, 12.4)))
    materials = {"ground": ground_material(), "film": Material(film_bsdf(thickness_nm, interior_ior))}
    camera = orbit_camera(centre, 62.0, 25.0, 30.0, 40.0, width, height)
    return Scene(camera, shapes, materials, sky(), max_depth=max_depth,
                 name=f"film-{thickness_nm:g}nm-interior-{interior_ior:g}")


def appearance_grid(width: int = 320, height: int = 240, max_depth: int = 8) -> list[tuple[str, Scene]]:
    """The six cells, rows by interior index, columns by thickness, as (label, scene)."""
    return [(f"{t:g} nm, interior {n:g}", appearance_grid_cell(t, n, width, height, max_depth))
            for n in INTERIOR_IORS for t in THICKNESSES_NM]
