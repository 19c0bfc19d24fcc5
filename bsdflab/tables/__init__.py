"""BSDF tables: the in-memory form, the OpenEXR file format and the on-disk cache."""
from .cache import cache_dir, cache_key, cached_table
from .data import FORMAT_VERSION, LOBES, TableData, TableGrid
from .file_format import read_attributes, read_table, write_table

__all__ = ["FORMAT_VERSION", "LOBES", "TableData", "TableGrid", "cache_dir", "cache_key",
           "cached_table", "read_attributes", "read_table", "write_table"]
