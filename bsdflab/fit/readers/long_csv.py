"""The fit's own long CSV (bsdflab.fit.data), read as it is (units declared by --units or
its ``# units:`` comment; the spectral keys of a sidecar do not apply)."""
from __future__ import annotations

from bsdflab.fit.data import COLUMNS, read_csv
from bsdflab.fit.readers.base import Reader


class LongCSV(Reader):
    name = "long"
    suffixes = (".csv",)
    description = "the fit's long CSV (one row per measurement: docs/fit_data.md)"
    long = True

    def claims(self, path: str, head: str) -> bool:
        first = next((ln for ln in head.splitlines() if ln.strip() and not ln.lstrip().startswith("#")), "")
        names = {c.strip() for c in first.split(",")}
        return {"angle_deg", "reflectance", "geometry"} <= names and names <= set(COLUMNS)

    def read_dataset(self, path: str, spec):
        return read_csv(path, spec.units)
