"""BSDF tables: tabulation, the in-memory form, the OpenEXR file format, the on-disk cache
and the table BSDF."""
from bsdflab.tables.cache import cache_dir, cache_key, cached_table
from bsdflab.tables.data import FORMAT_VERSION, LOBES, TableData, TableGrid
from bsdflab.tables.file_format import read_attributes, read_table, write_table
from bsdflab.tables.table_bsdf import TableBSDF
from bsdflab.tables.tabulate import tabulate

__all__ = ["FORMAT_VERSION", "LOBES", "TableBSDF", "TableData", "TableGrid", "cache_dir",
           "cache_key", "cached_table", "read_attributes", "read_table", "tabulate", "write_table"]
