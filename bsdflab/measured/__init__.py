"""Measured-BSDF formats: RGL ``.bsdf`` (Dupuy & Jakob 2018) writer and reader, MERL reader
(docs/measured.md)."""
from bsdflab.measured.measured_bsdf import Measured
from bsdflab.measured.merl import Merl
from bsdflab.measured.rgl import ExportReport, export_model, export_table, rgl_from_bsdf, write_rgl
from bsdflab.measured.rgl_file import RGLData, read_rgl

__all__ = ["ExportReport", "Measured", "Merl", "RGLData", "export_model", "export_table", "read_rgl",
           "rgl_from_bsdf", "write_rgl"]
