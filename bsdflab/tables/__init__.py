"""BSDF tables: tabulation, the in-memory form, the OpenEXR file format, the on-disk cache
and the table BSDF. Ask for a table with ``get(TableRequest.from_dict(...))``."""
from bsdflab.tables.cache import Fetched, cache_dir, cache_key, cached_table, get
from bsdflab.tables.data import FORMAT_VERSION, LOBES, TableData, TableGrid
from bsdflab.tables.file_format import read_attributes, read_table, write_table
from bsdflab.tables.request import TableRequest
from bsdflab.tables.table_bsdf import TableBSDF
from bsdflab.tables.tabulate import tabulate

__all__ = ["FORMAT_VERSION", "LOBES", "Fetched", "TableBSDF", "TableData", "TableGrid", "TableRequest",
           "cache_dir", "cache_key", "cached_table", "get", "read_attributes", "read_table", "tabulate",
           "write_table"]
