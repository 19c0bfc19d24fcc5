"""Ocean Optics OceanView / SpectraSuite tab-delimited text (.txt).

A header block of ``Key: value`` lines (spectrometer, integration time, averaging, boxcar),
then ``>>>>>Begin Spectral Data<<<<<`` (SpectraSuite: ``>>>>>Begin Processed Spectral
Data<<<<<``), then one ``wavelength<TAB>value`` line per pixel, optionally ended by
``>>>>>End ... Spectral Data<<<<<``. Some versions put a column line after the marker
(``W  D  R  S  P``: wavelength, dark, reference, sample, processed); the processed column is
read then. A decimal comma (locale) is read as a point: the delimiter is a tab.
"""
from __future__ import annotations

import re

import numpy as np

from bsdflab.fit.readers.base import Reader, Spectrum
from bsdflab.fit.readers.text import number, read_lines

_BEGIN = re.compile(r"^\s*>>>>>\s*Begin (Processed )?Spectral Data\s*<<<<<\s*$", re.IGNORECASE)
_END = re.compile(r"^\s*>>>>>\s*End (Processed )?Spectral Data\s*<<<<<\s*$", re.IGNORECASE)


class OceanViewText(Reader):
    name = "oceanview"
    suffixes = (".txt",)
    description = "Ocean Optics OceanView / SpectraSuite tab-delimited text with a header block"

    def claims(self, path: str, head: str) -> bool:
        return any(_BEGIN.match(ln) for ln in head.splitlines())

    def read(self, path: str, spec) -> list[Spectrum]:
        lines = read_lines(path)
        begin = next((i for i, ln in enumerate(lines) if _BEGIN.match(ln)), None)
        if begin is None:
            raise ValueError(f"{path}: no '>>>>>Begin Spectral Data<<<<<' line: not an OceanView/SpectraSuite "
                             f"text file")
        end = next((i for i in range(begin + 1, len(lines)) if _END.match(lines[i])), len(lines))
        body = [(i + 1, ln) for i, ln in enumerate(lines[begin + 1:end], begin + 1) if ln.strip()]
        column = 1
        if body and body[0][1].lstrip()[:1].isalpha():
            names = [c.strip() for c in body[0][1].split("\t")]
            if names[0].upper() != "W" or "P" not in [n.upper() for n in names]:
                raise ValueError(f"{path}: line {body[0][0]}: a column line after the marker must name W "
                                 f"(wavelength) first and P (processed), got {body[0][1].strip()!r}")
            column = [n.upper() for n in names].index("P")
            body = body[1:]
        if not body:
            raise ValueError(f"{path}: line {begin + 1}: no spectral data after the marker")
        width = column + 1
        wl, value = np.empty(len(body)), np.empty(len(body))
        for k, (n, text) in enumerate(body):
            cells = [c.strip() for c in text.split("\t")]
            if len(cells) < width:
                raise ValueError(f"{path}: line {n}: expected at least {width} tab-separated values, got "
                                 f"{len(cells)}")
            wl[k] = number(cells[0].replace(",", "."), f"{path}: line {n}, column 1", "the wavelength")
            value[k] = number(cells[column].replace(",", "."), f"{path}: line {n}, column {column + 1}",
                              "the value")
        rows = np.array([n for n, _ in body])
        return [Spectrum(wl, value, path, "", path, rows)]
