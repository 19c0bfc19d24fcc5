"""OpenPBR Surface as a MaterialX 1.39 document (``open_pbr_surface`` + ``surfacematerial``),
and its reading back into a comparison model.

Parameter mapping (OpenPBR Surface 1.1 specification): base_color = the body colour
(base_weight 1, metalness 0); specular_roughness = sqrt(GGX alpha) (OpenPBR squares it);
specular_ior = the fitted base index; thin_film_weight 1, thin_film_thickness in
micrometres, thin_film_ior = the fitted film index.
"""
from __future__ import annotations

import numpy as np

SHADER = "bsdflab_open_pbr_surface"
MATERIAL = "bsdflab_material"


def openpbr_inputs(params: dict) -> dict:
    """The open_pbr_surface inputs (name -> float or 3-tuple) of exported parameters."""
    return {"base_weight": 1.0, "base_color": tuple(params["base_color"]), "base_metalness": 0.0,
            "specular_weight": 1.0, "specular_color": (1.0, 1.0, 1.0),
            "specular_roughness": float(params["roughness"]), "specular_ior": float(params["base_ior"]),
            "thin_film_weight": 1.0 if params["film_thickness_nm"] > 0 else 0.0,
            "thin_film_thickness": float(params["film_thickness_nm"]) / 1000.0,
            "thin_film_ior": float(params["film_ior"])}


def openpbr_document(params: dict):
    """A MaterialX document (no libraries imported) holding the material."""
    import MaterialX as mx

    doc = mx.createDocument()
    shader = doc.addNode("open_pbr_surface", SHADER, "surfaceshader")
    for name, value in openpbr_inputs(params).items():
        shader.setInputValue(name, mx.Color3(*value) if isinstance(value, tuple) else float(value),
                             "color3" if isinstance(value, tuple) else "float")
    doc.addMaterialNode(MATERIAL, shader)
    return doc


def write_openpbr(params: dict, path: str) -> None:
    import MaterialX as mx

    mx.writeToXmlFile(openpbr_document(params), path)


def validate_mtlx(path: str) -> tuple[bool, str]:
    """(valid, message) of a .mtlx file against the MaterialX standard libraries."""
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, path)
    stdlib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), stdlib)
    doc.importLibrary(stdlib)
    return doc.validate()


def read_openpbr(path: str) -> dict:
    """The first open_pbr_surface of a .mtlx file as a comparison model: a dict with the
    film parameters (``thickness_nm``, ``film_ior``, ``base_ior``, ``thin_film_weight``,
    ``roughness``, ``base_color``) and ``rgb(cos_theta, n_outer=1)``, the specular colour
    MaterialX computes for it (Belcour-Barla, Gaussian fit, 2 terms)."""
    import MaterialX as mx

    from bsdflab.reference.approximations import belcour_barla_rgb

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, path)
    nodes = [n for n in doc.getNodes() if n.getCategory() == "open_pbr_surface"]
    if not nodes:
        raise ValueError(f"{path}: no open_pbr_surface node")
    node = nodes[0]
    defaults = {"thin_film_thickness": 0.5, "thin_film_ior": 1.4, "specular_ior": 1.5, "thin_film_weight": 0.0,
                "specular_roughness": 0.3, "base_color": (0.8, 0.8, 0.8)}

    def value(name):
        inp = node.getInput(name)
        if inp is None:
            return defaults[name]
        v = inp.getValue()
        return tuple(v.asTuple()) if hasattr(v, "asTuple") else float(v)

    out = {"thickness_nm": 1000.0 * value("thin_film_thickness"), "film_ior": value("thin_film_ior"),
           "base_ior": value("specular_ior"), "thin_film_weight": value("thin_film_weight"),
           "roughness": value("specular_roughness"), "base_color": value("base_color")}
    d, n2, n3, w = out["thickness_nm"], out["film_ior"], out["base_ior"], out["thin_film_weight"]
    out["rgb"] = lambda cos_theta, n_outer=1.0: (
        w * belcour_barla_rgb(n_outer, n2, n3, d, cos_theta)
        + (1 - w) * belcour_barla_rgb(n_outer, n_outer, n3, 0.0, np.asarray(cos_theta)))
    return out
