"""Reflectance data files for fitting (format: docs/fit_data.md).

A CSV file with a header row and the columns

    angle_deg, angle_out_deg, phi_deg, wavelength_nm, reflectance, sigma, geometry, series

``angle_out_deg`` may be left out of the header when no row is ``diffuse`` or ``brdf`` and
is empty for specular and total rows; ``phi_deg`` (the detector's azimuth, brdf rows only)
may be left out when no row is ``brdf``; ``series`` (a name per measured data set, e.g. one
per instrument or sample; empty: the one unnamed series) may be left out. Lines starting
with ``#`` are comments (kept, e.g. to label synthetic data), except ``# units: percent`` /
``# units: fraction``, which declare the reflectance units (bsdflab.fit.units: percent is
converted; undeclared values that look like percent are refused). Every problem is a
``ValueError`` naming the file, the line and the column.
"""
from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass, field

import numpy as np

from bsdflab.fit.units import near_mirror, percent_suspect, refuse_percent, scale, units_comment
from bsdflab.util.files import write_atomically

# index = the geometry code (0-2: the smooth C++ model's; brdf rows become diffuse ones there)
GEOMETRIES = ("specular", "diffuse", "total", "brdf")
MODEL_RANGE_NM = (350.0, 1000.0)                # Cauchy film index and melanin power law
COLUMNS = ("angle_deg", "angle_out_deg", "phi_deg", "wavelength_nm", "reflectance", "sigma", "geometry", "series")
OPTIONAL = ("angle_out_deg", "phi_deg", "series")
REQUIRED = tuple(c for c in COLUMNS if c not in OPTIONAL)
SPECULAR_TOLERANCE_DEG = 1e-6


@dataclass
class Dataset:
    """Measured (or simulated) reflectances, one entry per row of the file.

    geometry: int codes into GEOMETRIES; angle_out_deg is NaN except for diffuse and brdf
    rows, phi_deg NaN except for brdf rows (None: all NaN); series: the data set each row
    belongs to (strings; None: all "", the one unnamed series).
    """

    geometry: np.ndarray
    angle_deg: np.ndarray
    angle_out_deg: np.ndarray
    wavelength_nm: np.ndarray
    reflectance: np.ndarray
    sigma: np.ndarray
    comments: list[str] = field(default_factory=list)
    phi_deg: np.ndarray | None = None
    series: np.ndarray | None = None

    def __post_init__(self):
        if self.phi_deg is None:
            self.phi_deg = np.full(len(self.geometry), np.nan)
        if self.series is None:
            self.series = np.full(len(self.geometry), "", dtype=object)
        else:
            self.series = np.asarray(self.series, dtype=object)

    def series_names(self) -> list[str]:
        """The series in file order ("" is the unnamed one)."""
        return list(dict.fromkeys(self.series.tolist()))

    def __len__(self) -> int:
        return len(self.geometry)

    def with_reflectance(self, reflectance, sigma=None, comments=None) -> Dataset:
        return Dataset(self.geometry, self.angle_deg, self.angle_out_deg, self.wavelength_nm,
                       np.asarray(reflectance, float),
                       self.sigma if sigma is None else np.asarray(sigma, float),
                       self.comments if comments is None else list(comments), self.phi_deg, self.series)

    def groups(self) -> list[tuple[str, np.ndarray]]:
        """(label, row indices) per measured curve (series, geometry and angles), in file order."""
        keys: dict[tuple, list[int]] = {}
        for i in range(len(self)):
            g = GEOMETRIES[self.geometry[i]]
            key = (self.series[i], g, float(self.angle_deg[i]),
                   float(self.angle_out_deg[i]) if g in ("diffuse", "brdf") else None,
                   float(self.phi_deg[i]) if g == "brdf" else None)
            keys.setdefault(key, []).append(i)
        out = []
        for (series, g, a, b, phi), rows in keys.items():
            label = ((f"{series}: " if series else "") + f"{g} {a:g}°" + (f" → {b:g}°" if b is not None else "")
                     + (f" φ {phi:g}°" if phi is not None else ""))
            idx = np.array(rows)
            out.append((label, idx[np.argsort(self.wavelength_nm[idx], kind="stable")]))
        return out

    def to_csv_text(self) -> str:
        buf = io.StringIO()
        for c in self.comments:
            buf.write(f"# {c}\n")
        if self._needs_units_line():
            buf.write("# units: fraction\n")
        w = csv.writer(buf, lineterminator="\n")
        with_phi = bool(np.any(~np.isnan(self.phi_deg)))
        with_series = any(self.series)
        w.writerow([c for c in COLUMNS if (with_phi or c != "phi_deg") and (with_series or c != "series")])
        for i in range(len(self)):
            out = "" if math.isnan(self.angle_out_deg[i]) else repr(float(self.angle_out_deg[i]))
            phi = ["" if math.isnan(self.phi_deg[i]) else repr(float(self.phi_deg[i]))] if with_phi else []
            w.writerow([repr(float(self.angle_deg[i])), out, *phi, repr(float(self.wavelength_nm[i])),
                        f"{self.reflectance[i]:.10g}", f"{self.sigma[i]:.6g}",
                        GEOMETRIES[self.geometry[i]], *([self.series[i]] if with_series else [])])
        return buf.getvalue()

    def _needs_units_line(self) -> bool:
        """Whether reading the values back would take them for percent (fractions > 1.5 in a
        specular row, e.g. relative to a white standard): then the file declares them."""
        return any(self.percent_suspect(series) for series in self.series_names())

    def percent_suspect(self, series: str) -> tuple[str, int] | None:
        """bsdflab.fit.units.percent_suspect on one series: (why, row index) or None."""
        rows = np.flatnonzero(self.series == series)
        names = [GEOMETRIES[g] for g in self.geometry[rows]]
        near = near_mirror(names, self.angle_deg[rows], self.angle_out_deg[rows], self.phi_deg[rows])
        found = percent_suspect(names, self.reflectance[rows], near)
        return None if found is None else (found[0], int(rows[found[1]]))

    def write_csv(self, path: str | os.PathLike) -> None:
        """Write the file atomically (temp file + rename)."""
        text = self.to_csv_text()

        def write(tmp: str) -> None:
            with open(tmp, "w", encoding="utf-8") as f:
                f.write(text)

        write_atomically(path, write, suffix=".tmp.csv")


def _number(text: str, column: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{where}: {column} must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{where}: {column} must be finite, got {text!r}")
    return value


def read_csv(path: str | os.PathLike, units: str | None = None) -> Dataset:
    """Read and validate a data file; ValueError naming the file and line on bad input.
    ``units``: as parse_csv's."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8", newline="") as f:
            lines = f.read().splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise ValueError(f"cannot read data file {path}: {e}") from None
    return parse_csv(lines, path, units)


def parse_csv(lines: list[str], name: str = "<data>", units: str | None = None) -> Dataset:
    """Parse the lines of a data file; ``units`` ("percent"/"fraction") overrides the file's
    ``# units:`` comment (both None: values that look like percent are refused)."""
    comments, declared = [], None
    for number, ln in enumerate(lines, 1):
        if ln.lstrip().startswith("#"):
            text = ln.lstrip().lstrip("#").strip()
            found = units_comment(text, f"{name}: line {number}")
            if found is None:
                comments.append(text)
            elif declared is not None and found != declared:
                raise ValueError(f"{name}: line {number}: a second units comment says {found}, "
                                 f"an earlier one {declared}")
            else:
                declared = found
    units = units or declared
    numbered = [(i + 1, ln) for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")]
    if not numbered:
        raise ValueError(f"{name}: empty data file (no header, no rows)")
    header_line, header_text = numbered[0]
    header = [h.strip() for h in next(csv.reader([header_text]))]
    missing = [c for c in REQUIRED if c not in header]
    unknown = [c for c in header if c not in COLUMNS]
    if missing or unknown:
        raise ValueError(f"{name}: line {header_line}: header must name the columns {', '.join(COLUMNS)} "
                         f"({', '.join(OPTIONAL)} optional); missing {missing or 'none'}, unknown {unknown or 'none'}")
    if len(set(header)) != len(header):
        raise ValueError(f"{name}: line {header_line}: a column is named twice in the header")
    if len(numbered) == 1:
        raise ValueError(f"{name}: no data rows after the header")
    col = {c: header.index(c) for c in header}
    rows, seen, names, numbers = [], {}, [], []
    for number, text in numbered[1:]:
        where = f"{name}: line {number}"
        cells = [c.strip() for c in next(csv.reader([text]))]
        if len(cells) != len(header):
            raise ValueError(f"{where}: expected {len(header)} values, got {len(cells)}")
        g = cells[col["geometry"]].lower()
        if g not in GEOMETRIES:
            raise ValueError(f"{where}: unknown geometry {cells[col['geometry']]!r}; known: {', '.join(GEOMETRIES)}")
        a = _number(cells[col["angle_deg"]], "angle_deg", where)
        if not 0.0 <= a < 90.0:
            raise ValueError(f"{where}: angle_deg must be in [0, 90), got {a:g}")
        b = phi = math.nan
        out_text = cells[col["angle_out_deg"]] if "angle_out_deg" in col else ""
        phi_text = cells[col["phi_deg"]] if "phi_deg" in col else ""
        if g != "brdf" and phi_text:
            raise ValueError(f"{where}: phi_deg must be empty for a {g} row")
        if g == "brdf":
            if not out_text or not phi_text:
                raise ValueError(f"{where}: a brdf row needs angle_out_deg and phi_deg")
            b = _number(out_text, "angle_out_deg", where)
            if not 0.0 <= b < 90.0:
                raise ValueError(f"{where}: angle_out_deg of a brdf row (the detector's polar angle) must be "
                                 f"in [0, 90), got {b:g}")
            phi = _number(phi_text, "phi_deg", where)
            if not -180.0 <= phi <= 180.0:
                raise ValueError(f"{where}: phi_deg must be in [-180, 180], got {phi:g}")
        elif g == "diffuse":
            if not out_text:
                raise ValueError(f"{where}: a diffuse row needs angle_out_deg")
            b = _number(out_text, "angle_out_deg", where)
            if not -90.0 < b < 90.0:
                raise ValueError(f"{where}: angle_out_deg must be in (-90, 90), got {b:g}")
            if abs(b - a) < SPECULAR_TOLERANCE_DEG:
                raise ValueError(f"{where}: a diffuse row at the specular direction (angle_out_deg = "
                                 f"angle_deg) would include the mirror reflection; use geometry 'specular'")
        elif out_text:
            raise ValueError(f"{where}: angle_out_deg must be empty for a {g} row")
        wl = _number(cells[col["wavelength_nm"]], "wavelength_nm", where)
        if not MODEL_RANGE_NM[0] <= wl <= MODEL_RANGE_NM[1]:
            raise ValueError(f"{where}: wavelength_nm {wl:g} is outside the model's range "
                             f"{MODEL_RANGE_NM[0]:g}-{MODEL_RANGE_NM[1]:g} nm")
        r = _number(cells[col["reflectance"]], "reflectance", where)
        s = _number(cells[col["sigma"]], "sigma", where)
        if s <= 0:
            raise ValueError(f"{where}: sigma must be > 0, got {s:g}")
        series = cells[col["series"]] if "series" in col else ""
        key = (series, g, a, b if g in ("diffuse", "brdf") else None, phi if g == "brdf" else None, wl)
        if key in seen:
            raise ValueError(f"{where}: duplicate of line {seen[key]} (same series, geometry, angles and wavelength)")
        seen[key] = number
        rows.append((GEOMETRIES.index(g), a, b, wl, r, s, phi))
        names.append(series)
        numbers.append(number)
    arr = np.array(rows, dtype=float)
    ds = Dataset(arr[:, 0].astype(int), arr[:, 1], arr[:, 2], arr[:, 3], arr[:, 4], arr[:, 5], comments, arr[:, 6],
                 np.array(names, dtype=object))
    if units is None:
        for series in ds.series_names():
            found = ds.percent_suspect(series)
            if found:
                where = f"{name}: line {numbers[found[1]]}: column reflectance"
                where += f" (series {series})" if series else ""
                raise refuse_percent(where, found[0],
                                     "add the comment line '# units: percent' (or '# units: fraction' if the "
                                     "values are fractions above 1, e.g. relative to a white standard), or "
                                     "import it with 'bsdflab fit import FILE --units percent'")
    if units == "percent":
        ds.reflectance, ds.sigma = ds.reflectance * scale(units), ds.sigma * scale(units)
    return ds
