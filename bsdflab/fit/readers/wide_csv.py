"""Wide CSV/TSV: a wavelength column and one column per angle or per sample.

    wavelength_nm,R_15deg,R_20deg,R_20deg
    400,25.3,24.1,24.4

A header row names the columns; lines starting with ``#`` are comments (kept in the dataset). The delimiter is
the sidecar's ``delimiter``, else a tab or a semicolon if the header has one, else a comma.
The wavelength column is ``wavelength_column``, else the first whose name starts with
"wave", "lambda", "wl" or "nm", else the first. Every other column is one curve; the angle
comes from its name or the sidecar (bsdflab.fit.readers.assemble).
"""
from __future__ import annotations

import csv
import re

import numpy as np

from bsdflab.fit.readers.base import Reader, Spectrum
from bsdflab.fit.readers.text import number, read_lines

_WAVELENGTH = re.compile(r"^\s*(wave|lambda|λ|wl\b|nm\b)", re.IGNORECASE)


def _delimiter(header: str, spec) -> str:
    if spec.delimiter:
        return "\t" if spec.delimiter in ("\\t", "tab") else spec.delimiter
    if "\t" in header:
        return "\t"
    if ";" in header:
        return ";"
    return ","


class WideCSV(Reader):
    name = "wide"
    suffixes = (".csv", ".tsv", ".txt", ".dat")
    description = "a wavelength column and one column per angle or sample (CSV/TSV)"

    def claims(self, path: str, head: str) -> bool:
        return ">>>>>" not in head

    def read(self, path: str, spec) -> list[Spectrum]:
        lines = read_lines(path)
        numbered = [(i + 1, ln) for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")]
        if not numbered:
            raise ValueError(f"{path}: empty file (no header, no rows)")
        header_line, header_text = numbered[0]
        delimiter = _delimiter(header_text, spec)
        if delimiter == "," and spec.decimal == ",":
            raise ValueError(f"{path}: line {header_line}: decimal \",\" needs another delimiter (\";\" or a tab); "
                             f"set delimiter in the sidecar")
        header = [h.strip() for h in next(csv.reader([header_text], delimiter=delimiter))]
        if len(header) < 2:
            raise ValueError(f"{path}: line {header_line}: the header must name a wavelength column and at "
                             f"least one value column (delimiter {delimiter!r}; set delimiter in the sidecar)")
        if all(_is_number(h) for h in header[:2]):
            raise ValueError(f"{path}: line {header_line}: expected a header row naming the columns, got numbers")
        for j, h in enumerate(header):
            if not h:
                raise ValueError(f"{path}: line {header_line}, column {j + 1}: empty column name")
            if header.index(h) != j:
                raise ValueError(f"{path}: line {header_line}, column {j + 1}: column {h!r} is named twice "
                                 f"(replicates: give them distinct names, e.g. R_15deg_a and R_15deg_b)")
        if spec.wavelength_column is not None:
            if spec.wavelength_column not in header:
                raise ValueError(f"{path}: line {header_line}: no column named {spec.wavelength_column!r} "
                                 f"(wavelength_column); columns: {', '.join(header)}")
            wcol = header.index(spec.wavelength_column)
        else:
            wcol = next((j for j, h in enumerate(header) if _WAVELENGTH.match(h)), 0)
        if len(numbered) == 1:
            raise ValueError(f"{path}: no data rows after the header (line {header_line})")
        table = np.empty((len(numbered) - 1, len(header)))
        for r, (number_, text) in enumerate(numbered[1:]):
            cells = next(csv.reader([text], delimiter=delimiter))
            if len(cells) != len(header):
                raise ValueError(f"{path}: line {number_}: expected {len(header)} cells as in the header, "
                                 f"got {len(cells)}")
            for j, cell in enumerate(cells):
                table[r, j] = number(cell, f"{path}: line {number_}, column {j + 1} ({header[j]!r})",
                                     "the value", spec.decimal)
        rows = np.array([n for n, _ in numbered[1:]])
        comments = tuple(ln.lstrip().lstrip("#").strip() for ln in lines if ln.lstrip().startswith("#"))
        return [Spectrum(table[:, wcol], table[:, j], path, header[j], f"{path}: column {j + 1} {header[j]!r}", rows,
                         comments=comments) for j in range(len(header)) if j != wcol]


def _is_number(text: str) -> bool:
    try:
        float(text.replace(",", "."))
    except ValueError:
        return False
    return True
