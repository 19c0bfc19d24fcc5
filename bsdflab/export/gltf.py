"""glTF 2.0: a UV sphere (scene 0) and the snake's mesh (scene 1) with the material as KHR_materials_iridescence +
KHR_materials_ior, written with pygltflib (``.gltf`` with a ``.bin`` beside it, or one ``.glb``), and read back.

Mapping (Khronos extension specifications): baseColorFactor = body colour, metallic 0,
roughnessFactor = sqrt(GGX alpha); KHR_materials_ior.ior = the fitted base index (>= 1);
KHR_materials_iridescence: iridescenceFactor 1, iridescenceIor = the fitted film index,
iridescenceThicknessMinimum = Maximum = the fitted thickness in nm (no thickness texture:
the extension then uses the maximum). KHR_materials_specular is left out: its defaults
(factor 1, white) are what the fit assumes.
"""
from __future__ import annotations

import os

import numpy as np

EXTENSIONS = ("KHR_materials_iridescence", "KHR_materials_ior")


def uv_sphere(rings: int = 32, segments: int = 64):
    """(positions (N, 3) float32, normals (N, 3) float32, triangle indices (M,) uint32) of a
    unit sphere."""
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    pos = np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = (i * (segments + 1) + j).ravel()
    b, c, d = a + segments + 1, a + 1, a + segments + 2
    tris = np.concatenate([np.stack([a, b, c], 1), np.stack([c, b, d], 1)]).astype(np.uint32)
    keep = np.linalg.norm(np.cross(pos[tris[:, 1]] - pos[tris[:, 0]], pos[tris[:, 2]] - pos[tris[:, 0]]), axis=1) > 1e-9
    return pos.astype(np.float32), pos.astype(np.float32), tris[keep].ravel()


def material_extensions(params: dict) -> dict:
    return {"KHR_materials_ior": {"ior": float(params["base_ior"])},
            "KHR_materials_iridescence": {
                "iridescenceFactor": 1.0 if params["film_thickness_nm"] > 0 else 0.0,
                "iridescenceIor": float(params["film_ior"]),
                "iridescenceThicknessMinimum": float(params["film_thickness_nm"]),
                "iridescenceThicknessMaximum": float(params["film_thickness_nm"])}}


def _meshes():
    """[(name, positions, normals, indices)]: the unit sphere, then the snake (y up, metres)."""
    from bsdflab.export.snake_mesh import snake_mesh

    sn = snake_mesh(y_up=True)
    snake = (sn["positions"].astype(np.float32), sn["normals"].astype(np.float32),
             sn["indices"].astype(np.uint32).ravel())
    return [("sphere", *uv_sphere()), ("snake", *snake)]


def gltf_document(params: dict, bin_uri: str | None):
    """(pygltflib.GLTF2, binary blob): scene 0 (the default) the sphere, scene 1 the snake's
    mesh (bsdflab.export.snake_mesh, no scale texture), both with the material."""
    import pygltflib as g

    chunks, views, accessors, meshes, offset = [], [], [], [], 0
    for k, (name, pos, nrm, idx) in enumerate(_meshes()):
        for data, target in ((idx, g.ELEMENT_ARRAY_BUFFER), (pos, g.ARRAY_BUFFER), (nrm, g.ARRAY_BUFFER)):
            chunks.append(data.tobytes())
            views.append(g.BufferView(buffer=0, byteOffset=offset, byteLength=data.nbytes, target=target))
            offset += data.nbytes
        v = 3 * k
        accessors += [g.Accessor(bufferView=v, componentType=g.UNSIGNED_INT, count=len(idx), type=g.SCALAR,
                                 min=[int(idx.min())], max=[int(idx.max())]),
                      g.Accessor(bufferView=v + 1, componentType=g.FLOAT, count=len(pos), type=g.VEC3,
                                 min=pos.min(0).tolist(), max=pos.max(0).tolist()),
                      g.Accessor(bufferView=v + 2, componentType=g.FLOAT, count=len(nrm), type=g.VEC3,
                                 min=nrm.min(0).tolist(), max=nrm.max(0).tolist())]
        meshes.append(g.Mesh(name=name, primitives=[g.Primitive(attributes=g.Attributes(POSITION=v + 1, NORMAL=v + 2),
                                                                indices=v, material=0)]))
    blob = b"".join(chunks)
    doc = g.GLTF2(
        asset=g.Asset(version="2.0", generator="bsdflab export"),
        scene=0, scenes=[g.Scene(name="sphere", nodes=[0]), g.Scene(name="snake", nodes=[1])],
        nodes=[g.Node(mesh=0, name="sphere"), g.Node(mesh=1, name="snake")], meshes=meshes,
        materials=[g.Material(name="bsdflab_material",
                              pbrMetallicRoughness=g.PbrMetallicRoughness(
                                  baseColorFactor=[*map(float, params["base_color"]), 1.0],
                                  metallicFactor=0.0, roughnessFactor=float(params["roughness"])),
                              extensions=material_extensions(params))],
        extensionsUsed=list(EXTENSIONS),
        buffers=[g.Buffer(byteLength=len(blob), uri=bin_uri)], bufferViews=views, accessors=accessors)
    return doc, blob


def gltf_writers(params: dict, path: str) -> list[tuple[str, object, str]]:
    """write_together items for ``path`` (.glb: one file; .gltf: the JSON and its .bin)."""
    if path.lower().endswith(".glb"):
        def write_glb(tmp):
            doc, blob = gltf_document(params, None)
            doc.set_binary_blob(blob)
            doc.save_binary(tmp)
        return [(path, write_glb, ".glb")]
    bin_path = os.path.splitext(path)[0] + ".bin"
    doc, blob = gltf_document(params, os.path.basename(bin_path))

    def write_json(tmp):
        with open(tmp, "w") as f:
            f.write(doc.gltf_to_json())

    def write_bin(tmp):
        with open(tmp, "wb") as f:
            f.write(blob)
    return [(path, write_json, ".gltf"), (bin_path, write_bin, ".bin")]


def read_gltf(path: str) -> dict:
    """The first material's thin film as a comparison model: ``thickness_nm`` (the
    extension's maximum), ``film_ior``, ``base_ior``, ``iridescence_factor``, ``roughness``,
    ``base_color``, and ``rgb(cos_theta, n_outer=1)`` the extension's own reflectance."""
    import pygltflib as g

    from bsdflab.reference.approximations import gltf_iridescence_rgb

    doc = g.GLTF2().load(path)
    if not doc.materials:
        raise ValueError(f"{path}: no material")
    m = doc.materials[0]
    ext = m.extensions or {}
    ir = ext.get("KHR_materials_iridescence", {})
    out = {"thickness_nm": float(ir.get("iridescenceThicknessMaximum", 400.0)),
           "film_ior": float(ir.get("iridescenceIor", 1.3)),
           "iridescence_factor": float(ir.get("iridescenceFactor", 0.0)),
           "base_ior": float(ext.get("KHR_materials_ior", {}).get("ior", 1.5)),
           "roughness": float(m.pbrMetallicRoughness.roughnessFactor),
           "base_color": tuple(m.pbrMetallicRoughness.baseColorFactor[:3])}
    d, n2, n3, w = out["thickness_nm"], out["film_ior"], out["base_ior"], out["iridescence_factor"]
    out["rgb"] = lambda cos_theta, n_outer=1.0: (
        w * gltf_iridescence_rgb(n_outer, n2, n3, d, cos_theta)
        + (1 - w) * gltf_iridescence_rgb(n_outer, n_outer, n3, 1e3, np.asarray(cos_theta)))
    return out
