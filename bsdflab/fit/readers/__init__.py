"""Instrument and spreadsheet files -> the fit's dataset (docs/fit_data.md, "Importing").

    from bsdflab.fit.readers import import_files, load_spec
    dataset, notes = import_files(["angles.csv"], load_spec("angles.csv.toml"))

One module per format registers a ``Reader`` in ``READERS`` (base.py); ``assemble`` turns
the curves they return into rows with the sidecar's geometry, angles, units, reference and
sigma. Every problem is a ValueError naming the file, the line and the column (or the XML
element, for formats without lines).
"""
from __future__ import annotations

import os

import numpy as np

from bsdflab.fit.data import Dataset, parse_csv
from bsdflab.fit.readers.assemble import assemble
from bsdflab.fit.readers.base import READERS, Reader, Spectrum, reader_for
from bsdflab.fit.readers.sidecar import ImportSpec, load_spec, parse_spec

__all__ = ["READERS", "ImportSpec", "Reader", "Spectrum", "default_sidecar", "import_files", "load_spec",
           "parse_spec", "reader_for"]

# keys that describe spectra; the long CSV already carries all of this per row
_SPECTRAL = ("geometry", "angle_deg", "angles_deg", "angle_out_deg", "phi_deg", "name_pattern", "wavelength_column",
             "delimiter", "wavelengths", "reference", "columns", "files")


def default_sidecar(path: str) -> str | None:
    """``<file>.toml`` (e.g. angles.csv.toml), else ``<stem>.toml`` beside it, if one exists."""
    for candidate in (path + ".toml", os.path.splitext(path)[0] + ".toml"):
        if os.path.isfile(candidate) and os.path.abspath(candidate) != os.path.abspath(path):
            return candidate
    return None


def import_files(paths: list[str], spec: ImportSpec) -> tuple[Dataset, list[str]]:
    """Read ``paths`` (one format, detected or ``spec.format``) into one dataset, with notes."""
    if not paths:
        raise ValueError("no files to import")
    for p in paths:
        if not os.path.isfile(p):
            raise ValueError(f"{p}: no such file")
    readers = [reader_for(p, spec.format) for p in paths]
    kinds = {r.long for r in readers}
    if len(kinds) > 1:
        raise ValueError("cannot mix the long CSV with spectra files in one import: "
                         + ", ".join(f"{p} ({r.name})" for p, r in zip(paths, readers)))
    if readers[0].long:
        return _long(paths, readers, spec)
    spectra = [s for p, r in zip(paths, readers) for s in r.read(p, spec)]
    return assemble(spectra, spec)


def _long(paths: list[str], readers: list[Reader], spec: ImportSpec) -> tuple[Dataset, list[str]]:
    given = [k for k in _SPECTRAL if getattr(spec, k) is not None and not (isinstance(getattr(spec, k), dict)
                                                                       and not getattr(spec, k))]
    if given or spec.sigma_absolute or spec.sigma_relative:
        raise ValueError(f"{spec.source}: {', '.join(given) or '[sigma]'} do not apply to the long CSV (each row "
                         f"names its geometry, angles and sigma); only units and series do")
    parts = [r.read_dataset(p, spec) for p, r in zip(paths, readers)]
    if spec.series is not None:
        for d in parts:
            d.series = np.where(d.series == "", spec.series, d.series).astype(object)
    fields = ("geometry", "angle_deg", "angle_out_deg", "wavelength_nm", "reflectance", "sigma")
    ds = Dataset(*(np.concatenate([getattr(d, f) for d in parts]) for f in fields),
                 [c for d in parts for c in d.comments],
                 np.concatenate([d.phi_deg for d in parts]), np.concatenate([d.series for d in parts]))
    seen: dict[tuple, str] = {}
    for path, d in zip(paths, parts):
        for i in range(len(d)):
            key = (d.series[i], int(d.geometry[i]), float(d.angle_deg[i]), str(d.angle_out_deg[i]), str(d.phi_deg[i]),
                   float(d.wavelength_nm[i]))
            if key in seen and seen[key] != path:
                raise ValueError(f"{path}: the row at {d.angle_deg[i]:g}° and {d.wavelength_nm[i]:g} nm (series "
                                 f"{d.series[i]!r}) repeats one of {seen[key]}: give the files different series "
                                 f"(a series column) or import them apart")
            seen[key] = path
    ds = parse_csv(ds.to_csv_text().splitlines(), "the imported dataset", units="fraction")
    return ds, [f"{len(ds)} rows from {len(paths)} long CSV file(s)"]
