"""BSDF tables: tabulation, the in-memory form, the OpenEXR file format, the on-disk cache
and the table BSDF."""
from .cache import cache_dir, cache_key, cached_table
from .data import FORMAT_VERSION, LOBES, TableData, TableGrid
from .file_format import read_attributes, read_table, write_table
from .table_bsdf import TableBSDF
from .tabulate import tabulate

__all__ = ["FORMAT_VERSION", "LOBES", "TableBSDF", "TableData", "TableGrid", "cache_dir",
           "cache_key", "cached_table", "read_attributes", "read_table", "tabulate", "write_table"]
