"""USD (``.usda``, usd-core): a sphere bound to the OpenPBR material as MaterialX nodes.

The material is authored the way USD's MaterialX schema carries it (UsdShade with
``info:id = "ND_open_pbr_surface_surfaceshader"`` and its inputs, connected to the
material's ``outputs:mtlx:surface``), so USD renderers with MaterialX support (Hydra Storm,
RenderMan, Arnold) read the same open_pbr_surface the .mtlx export holds.
"""
from __future__ import annotations

from bsdflab.export.openpbr import openpbr_inputs

NODEDEF = "ND_open_pbr_surface_surfaceshader"


def write_usd(params: dict, path: str) -> None:
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    root = UsdGeom.Xform.Define(stage, "/bsdflab")
    stage.SetDefaultPrim(root.GetPrim())
    sphere = UsdGeom.Sphere.Define(stage, "/bsdflab/sphere")
    sphere.GetRadiusAttr().Set(1.0)
    material = UsdShade.Material.Define(stage, "/bsdflab/Looks/bsdflab_material")
    shader = UsdShade.Shader.Define(stage, "/bsdflab/Looks/bsdflab_material/open_pbr_surface")
    shader.CreateIdAttr(NODEDEF)
    for name, value in openpbr_inputs(params).items():
        if isinstance(value, tuple):
            shader.CreateInput(name, Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*value))
        else:
            shader.CreateInput(name, Sdf.ValueTypeNames.Float).Set(float(value))
    out = shader.CreateOutput("surface", Sdf.ValueTypeNames.Token)
    material.CreateSurfaceOutput("mtlx").ConnectToSource(out)
    UsdShade.MaterialBindingAPI.Apply(sphere.GetPrim()).Bind(material)
    stage.GetRootLayer().Export(path)


def read_usd_inputs(path: str) -> dict:
    """The open_pbr_surface inputs of a .usda written by ``write_usd`` (name -> value)."""
    from pxr import Usd, UsdShade

    stage = Usd.Stage.Open(path)
    for prim in stage.Traverse():
        shader = UsdShade.Shader(prim)
        if shader and shader.GetIdAttr().Get() == NODEDEF:
            return {i.GetBaseName(): i.Get() for i in shader.GetInputs()}
    raise ValueError(f"{path}: no {NODEDEF} shader")
