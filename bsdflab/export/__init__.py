"""Materials leave bsdflab: fitted exports to OpenPBR/MaterialX, glTF, USD and Blender.

``export(model, fmt, out)`` fits the target standard's single-film parameters to bsdflab's
exact film by CIEDE2000 (``fit``), writes the target's file(s) and a report with the
Delta E00 map; ``read_openpbr`` / ``read_gltf`` turn an existing asset's thin film into a
comparison model. See docs/export.md.
"""
from bsdflab.export.exporter import export
from bsdflab.export.gltf import read_gltf
from bsdflab.export.openpbr import read_openpbr
from bsdflab.export.targets import FORMATS, TARGETS

__all__ = ["FORMATS", "TARGETS", "export", "read_gltf", "read_openpbr"]
