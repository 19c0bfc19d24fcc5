"""Avantes AvaSoft text export (.ttt reflectance/transmittance, .trt).

    1305084U1-my comment
    Integration time: 10.00 ms
    Average: 1 scans
    Nr of pixels used for smoothing: 0
    Data measured with spectrometer name: 1305084U1
    Wave   ;Sample   ;Dark     ;Reference;Reflectance
    [nm]   ;[counts] ;[counts] ;[counts] ;[%]

    400.12;  2210.5;  102.0;  4110.0;  52.6

A header block, a column line starting with ``Wave`` (cells separated by ``;``), an
optional unit line (``[nm] ;[counts] ...``) and the data. The processed column (the last
one that is not Wave, Sample, Dark or Reference) is read, in the units its unit line names
(``[%]``: percent); without one, the ratio (Sample - Dark) / (Reference - Dark) is the value,
as a fraction. A decimal comma (AvaSoft on a comma locale) is read as a point.
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.readers.base import Reader, Spectrum
from bsdflab.fit.readers.text import number, read_lines

RAW = {"wave": "wave", "sample": "sample", "scope": "sample", "dark": "dark", "ref": "reference",
       "reference": "reference"}


class AvantesText(Reader):
    name = "avantes-ttt"
    suffixes = (".ttt", ".trt")
    description = "Avantes AvaSoft text export (.ttt, .trt)"

    def read(self, path: str, spec) -> list[Spectrum]:
        lines = read_lines(path)
        head = next((i for i, ln in enumerate(lines) if ln.strip().lower().startswith("wave")), None)
        if head is None:
            raise ValueError(f"{path}: no column line starting with 'Wave': not an AvaSoft text export")
        sep = ";" if ";" in lines[head] else ("\t" if "\t" in lines[head] else ",")
        names = [c.strip() for c in lines[head].split(sep)]
        while names and not names[-1]:
            names.pop()
        kinds = [RAW.get(n.lower()) for n in names]
        units_line = head + 1 if head + 1 < len(lines) and lines[head + 1].strip().startswith("[") else None
        units = [c.strip() for c in lines[units_line].split(sep)] if units_line is not None else []
        processed = [j for j, k in enumerate(kinds) if k is None]
        last = head if units_line is None else units_line
        body = [(n, ln) for n, ln in enumerate(lines[last + 1:], last + 2) if ln.strip()]
        if not body:
            raise ValueError(f"{path}: line {head + 1}: no data rows after the column line")
        table = np.empty((len(body), len(names)))
        for r, (n, text) in enumerate(body):
            cells = [c.strip() for c in text.split(sep)]
            while len(cells) > len(names) and not cells[-1]:
                cells.pop()
            if len(cells) != len(names):
                raise ValueError(f"{path}: line {n}: expected {len(names)} values as in the column line "
                                 f"(line {head + 1}), got {len(cells)}")
            for j, cell in enumerate(cells):
                table[r, j] = number(cell.replace(",", "."), f"{path}: line {n}, column {j + 1} ({names[j]!r})",
                                     "the value")
        rows = np.array([n for n, _ in body])
        wl = table[:, 0]
        if processed:
            j = processed[-1]
            unit = units[j].strip("[] ").lower() if j < len(units) else ""
            stated = "percent" if unit == "%" else ("fraction" if unit in ("", "-", "fraction") and units else None)
            return [Spectrum(wl, table[:, j], path, "", f"{path}: column {j + 1} {names[j]!r}", rows, stated)]
        need = [k for k in ("sample", "dark", "reference") if k not in kinds]
        if need:
            raise ValueError(f"{path}: line {head + 1}: no processed column and no {', '.join(need)} column to "
                             f"compute the reflectance from")
        s, d, ref = (table[:, kinds.index(k)] for k in ("sample", "dark", "reference"))
        denom = ref - d
        bad = np.flatnonzero(denom <= 0)
        if bad.size:
            raise ValueError(f"{path}: line {rows[bad[0]]}: Reference - Dark is {denom[bad[0]]:g} (<= 0): "
                             f"the reflectance cannot be computed there")
        return [Spectrum(wl, (s - d) / denom, path, "", f"{path}: (Sample - Dark) / (Reference - Dark)", rows,
                         "fraction")]
