"""Spectra from instrument files -> the fit's long dataset.

Each curve gets its geometry, angles and series: the sidecar's entry for the column or
file; then ``angles_deg`` in order; then ``name_pattern`` on the column's name, else the
file's; then the sidecar's ``angle_deg``; then the angle in the column's name, then in the
file's name. Its units: declared, else what the file states, else the units rule. The
wavelength grid: ``[wavelengths]`` (resampled by linear interpolation), else the files' own,
which must then agree; cropped to the model's range. Curves with the same series, geometry
and angles are replicates: their mean is the value and
sigma^2 = SE^2 + absolute^2 + (relative * mean)^2, SE = sample std / sqrt(n) over the
replicates (0 for one curve, or with ``replicates = false``). A reference standard multiplies
value and sigma (its own uncertainty is not propagated).
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from bsdflab.fit.data import GEOMETRIES, MODEL_RANGE_NM, SPECULAR_TOLERANCE_DEG, Dataset, parse_csv
from bsdflab.fit.readers.angles import angle_from_name, pattern_match, stem
from bsdflab.fit.readers.base import Spectrum, reader_for
from bsdflab.fit.readers.sidecar import Curve, ImportSpec
from bsdflab.fit.units import check_units, near_mirror, percent_suspect, refuse_percent, scale

UNITS_HOW = "units = \"percent\" in the sidecar or --units percent"


@dataclass
class Placed:
    """A spectrum with where it belongs."""

    spectrum: Spectrum
    geometry: str
    angle_deg: float
    angle_out_deg: float
    phi_deg: float
    series: str
    units: str | None


def _curve_entry(spectrum: Spectrum, spec: ImportSpec, used: set) -> Curve:
    if spectrum.name:
        key = ("columns", spectrum.name)
        entry = spec.columns.get(spectrum.name)
    else:
        base = os.path.basename(spectrum.file)
        key = ("files", base if base in spec.files else stem(spectrum.file))
        entry = spec.files.get(key[1])
    if entry is not None:
        used.add(key)
    return entry or Curve()


def _label(spectrum: Spectrum) -> str:
    return spectrum.name or stem(spectrum.file)


def _kept(spectra: list[Spectrum], spec: ImportSpec) -> list[tuple[Curve, Spectrum]]:
    """Each spectrum with its sidecar entry, less the ignored; every entry must name a curve."""
    used: set = set()
    entries = [(_curve_entry(s, spec, used), s) for s in spectra]
    for table, names in (("columns", spec.columns), ("files", spec.files)):
        for name in names:
            if (table, name) not in used:
                raise ValueError(f"{spec.source}: [{table}.\"{name}\"] names a {table[:-1]} that none of the files has")
    kept = [(c, s) for c, s in entries if not c.ignore]
    if not kept:
        raise ValueError("no curves to import (every column or file is ignored)")
    if spec.angles_deg is not None and len(spec.angles_deg) != len(kept):
        raise ValueError(f"{spec.source}: angles_deg gives {len(spec.angles_deg)} angles for {len(kept)} curves "
                         f"({', '.join(_label(s) for _, s in kept)})")
    return kept


def _angle(curve: Curve, spec: ImportSpec, k: int, groups: dict[str, str], s: Spectrum) -> float:
    """The angle of incidence of the k-th kept curve, by the module docstring's order."""
    angle = curve.angle_deg
    if angle is None and spec.angles_deg is not None:
        angle = spec.angles_deg[k]
    if angle is None and "angle" in groups:
        angle = _group_number(groups["angle"], s.where)
    if angle is None:
        angle = spec.angle_deg
    if angle is None:
        angle = angle_from_name(_label(s), s.where)
    if angle is None and s.name:
        angle = angle_from_name(stem(s.file), s.where)   # one file per angle, columns per sample
    if angle is None:
        raise ValueError(f"{s.where}: no angle of incidence: the name {_label(s)!r} holds none (e.g. R_15deg, "
                         f"theta=15) and the sidecar gives none (angle_deg, angles_deg, [columns] or [files])")
    if not 0.0 <= angle < 90.0:
        raise ValueError(f"{s.where}: the angle of incidence must be in [0, 90), got {angle:g}")
    return angle


def _geometry(curve: Curve, spec: ImportSpec, s: Spectrum) -> str:
    geometry = curve.geometry or spec.geometry
    if geometry is None:
        raise ValueError(f"{s.where}: no geometry: declare geometry = \"specular\" (or diffuse, total, brdf) "
                         f"in the sidecar or with --geometry")
    return geometry


def _detector(curve: Curve, spec: ImportSpec, geometry: str, angle: float,
              s: Spectrum) -> tuple[float | None, float | None]:
    """The detector's angle and azimuth, None where the geometry has none."""
    out_angle = curve.angle_out_deg if curve.angle_out_deg is not None else spec.angle_out_deg
    phi = curve.phi_deg if curve.phi_deg is not None else spec.phi_deg
    if geometry in ("diffuse", "brdf") and out_angle is None:
        raise ValueError(f"{s.where}: a {geometry} curve needs angle_out_deg (the detector's angle)")
    if geometry == "brdf" and phi is None:
        raise ValueError(f"{s.where}: a brdf curve needs phi_deg (the detector's azimuth)")
    if geometry in ("specular", "total"):
        return None, None
    if geometry == "diffuse":
        if abs(out_angle - angle) < SPECULAR_TOLERANCE_DEG:
            raise ValueError(f"{s.where}: a diffuse curve at the mirror direction (angle_out_deg = angle); "
                             f"use geometry specular")
        return out_angle, None
    if not 0.0 <= out_angle < 90.0:
        raise ValueError(f"{s.where}: angle_out_deg of a brdf curve must be in [0, 90), got {out_angle:g}")
    return out_angle, phi


def _units(spec: ImportSpec, s: Spectrum) -> str | None:
    """The declared units, else the file's; the two must agree where both are given."""
    units = spec.units
    if units is not None and s.units is not None and s.units != units:
        raise ValueError(f"{s.where}: the file states its values are in {s.units}, the sidecar/options say "
                         f"{units}")
    return units or s.units


def place(spectra: list[Spectrum], spec: ImportSpec) -> list[Placed]:
    """Geometry, angles, series and units of every curve (the order of the module docstring)."""
    out = []
    for k, (curve, s) in enumerate(_kept(spectra, spec)):
        groups = _pattern(spec.name_pattern, s) if spec.name_pattern else {}
        angle = _angle(curve, spec, k, groups, s)
        geometry = _geometry(curve, spec, s)
        out_angle, phi = _detector(curve, spec, geometry, angle, s)
        series = curve.series if curve.series is not None else groups.get("series", spec.series or "")
        units = _units(spec, s)
        out.append(Placed(s, geometry, float(angle), np.nan if out_angle is None else float(out_angle),
                          np.nan if phi is None else float(phi), series, units))
    return out


def _pattern(pattern: str, s: Spectrum) -> dict[str, str]:
    """name_pattern's groups in the column's name, else in the file's name."""
    if s.name:
        try:
            return pattern_match(pattern, s.name, s.where)
        except ValueError:
            pass
    return pattern_match(pattern, stem(s.file), s.where)


def _group_number(text: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{where}: name_pattern's angle group matched {text!r}, not a number") from None


def _increasing(s: Spectrum) -> tuple[np.ndarray, np.ndarray]:
    wl, v = s.wavelength_nm, s.value
    if len(wl) > 1 and np.all(np.diff(wl) < 0):
        return wl[::-1], v[::-1]
    bad = np.flatnonzero(np.diff(wl) <= 0)
    if bad.size:
        raise ValueError(f"{s.at(int(bad[0]) + 1)}: the wavelengths must increase ({wl[bad[0]]:g} then "
                         f"{wl[bad[0] + 1]:g} nm)")
    return wl, v


def _grid(placed: list[Placed], spec: ImportSpec) -> np.ndarray:
    lo, hi = MODEL_RANGE_NM
    if spec.wavelengths is not None:
        g = spec.wavelengths
        outside = g[(g < lo) | (g > hi)]
        if outside.size:
            raise ValueError(f"{spec.source}: [wavelengths] {outside[0]:g} nm is outside the model's range "
                             f"{lo:g}-{hi:g} nm")
        return g
    first = _increasing(placed[0].spectrum)[0]
    for p in placed[1:]:
        wl = _increasing(p.spectrum)[0]
        if len(wl) != len(first) or not np.allclose(wl, first, rtol=0, atol=1e-6):
            raise ValueError(f"{p.spectrum.where}: its wavelengths differ from {placed[0].spectrum.where}'s; give a "
                             f"common grid ([wavelengths] start/stop/step in the sidecar or --wavelengths)")
    g = first[(first >= lo) & (first <= hi)]
    if g.size == 0:
        raise ValueError(f"{placed[0].spectrum.where}: no wavelength inside the model's range {lo:g}-{hi:g} nm")
    return g


def _on_grid(p: Placed, grid: np.ndarray, resample: bool) -> np.ndarray:
    wl, v = _increasing(p.spectrum)
    if not resample:
        return v[np.searchsorted(wl, grid - 1e-6)]
    if grid[0] < wl[0] or grid[-1] > wl[-1]:
        raise ValueError(f"{p.spectrum.where}: covers {wl[0]:g}-{wl[-1]:g} nm, the grid asks for "
                         f"{grid[0]:g}-{grid[-1]:g} nm")
    return np.interp(grid, wl, v)


def _check_units(placed: list[Placed]) -> None:
    """The units rule on every series' undeclared curves (bsdflab.fit.units)."""
    for series in dict.fromkeys(p.series for p in placed):
        loose = [p for p in placed if p.series == series and p.units is None]
        if not loose:
            continue
        geometry = np.concatenate([np.full(len(p.spectrum.value), p.geometry, dtype=object) for p in loose])
        values = np.concatenate([p.spectrum.value for p in loose])
        near = np.concatenate([near_mirror(np.full(len(p.spectrum.value), p.geometry, dtype=object), p.angle_deg,
                                           p.angle_out_deg, p.phi_deg) for p in loose])
        # only what the fit will see: the model's wavelength range
        inside = np.concatenate([(p.spectrum.wavelength_nm >= MODEL_RANGE_NM[0])
                                 & (p.spectrum.wavelength_nm <= MODEL_RANGE_NM[1]) for p in loose])
        found = percent_suspect(geometry[inside], values[inside], near[inside])
        if found:
            k = int(np.flatnonzero(inside)[found[1]])
            sizes = np.cumsum([len(p.spectrum.value) for p in loose])
            j = int(np.searchsorted(sizes, k, side="right"))
            s = loose[j].spectrum
            raise refuse_percent(s.at(k - (sizes[j - 1] if j else 0)), found[0], UNITS_HOW)


def _reference(spec: ImportSpec, grid: np.ndarray) -> tuple[np.ndarray, str]:
    ref = spec.reference
    if ref is None:
        return np.ones_like(grid), ""
    if ref.reflectance is not None:
        value = ref.reflectance * scale(ref.units or "fraction")
        return np.full_like(grid, value), f"relative to a white standard of reflectance {value:g}"
    reader = reader_for(ref.file, ref.format)
    if reader.long:
        raise ValueError(f"{ref.file}: a reference spectrum is a spectrum file (e.g. a wide CSV with one column), "
                         f"not the long dataset")
    curves = reader.read(ref.file, ImportSpec())
    if len(curves) != 1:
        raise ValueError(f"{ref.file}: a reference spectrum file must hold one curve, got {len(curves)}")
    s = curves[0]
    units = ref.units or s.units
    if units is None:
        if float(np.max(s.value)) > 1.5:
            raise refuse_percent(s.at(int(np.argmax(s.value))), f"a reference reflectance of {np.max(s.value):g}",
                                 "units = \"percent\" in [reference]")
        units = "fraction"
    wl, v = _increasing(s)
    if grid[0] < wl[0] or grid[-1] > wl[-1]:
        raise ValueError(f"{s.where}: the reference covers {wl[0]:g}-{wl[-1]:g} nm, the data "
                         f"{grid[0]:g}-{grid[-1]:g} nm")
    return np.interp(grid, wl, v) * scale(units), f"relative to the reference spectrum {os.path.basename(ref.file)}"


def assemble(spectra: list[Spectrum], spec: ImportSpec) -> tuple[Dataset, list[str]]:
    """The dataset, and notes for the user (what was averaged, cropped, converted)."""
    placed = place(spectra, spec)
    _check_units(placed)
    grid = _grid(placed, spec)
    resample = spec.wavelengths is not None
    ref, ref_note = _reference(spec, grid)
    groups: dict[tuple, list[Placed]] = {}
    for p in placed:
        groups.setdefault((p.series, p.geometry, p.angle_deg, p.angle_out_deg, p.phi_deg), []).append(p)
    cols: dict[str, list] = {k: [] for k in ("geometry", "angle", "out", "phi", "wl", "value", "sigma", "series")}
    notes, reps = [], []
    for (series, geometry, angle, out_angle, phi), members in groups.items():
        values = np.array([_on_grid(p, grid, resample) * scale(p.units or "fraction") for p in members])
        n = len(members)
        mean = values.mean(axis=0)
        se = values.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 and spec.sigma_replicates else np.zeros_like(mean)
        factor = scale(members[0].units or "fraction")
        sigma = np.sqrt(se ** 2 + (spec.sigma_absolute * factor) ** 2 + (spec.sigma_relative * mean) ** 2)
        label = (f"series {series!r}, " if series else "") + f"{geometry} {angle:g}°" \
            + ("" if np.isnan(out_angle) else f" -> {out_angle:g}°") + ("" if np.isnan(phi) else f" phi {phi:g}°")
        zero = np.flatnonzero(sigma <= 0)
        if zero.size:
            why = ("one curve only" if n == 1 else
                   "the replicates agree exactly" if spec.sigma_replicates else "[sigma] replicates = false")
            raise ValueError(f"{members[0].spectrum.where}: sigma is 0 for {label} at {grid[zero[0]]:g} nm ({why}); "
                             f"declare [sigma] absolute and/or relative in the sidecar (or --sigma-absolute, "
                             f"--sigma-relative), or give replicates")
        reps.append(n)
        m = len(grid)
        cols["geometry"] += [GEOMETRIES.index(geometry)] * m
        cols["angle"] += [angle] * m
        cols["out"] += [out_angle] * m
        cols["phi"] += [phi] * m
        cols["wl"] += grid.tolist()
        cols["value"] += (mean * ref).tolist()
        cols["sigma"] += (sigma * ref).tolist()
        cols["series"] += [series] * m
    files = list(dict.fromkeys(os.path.basename(s.file) for s in spectra))
    comments = list(dict.fromkeys(c for s in spectra for c in s.comments))
    comments.append(f"imported by bsdflab fit import from {', '.join(files)}")
    units_used = sorted({p.units or "fraction (undeclared)" for p in placed})
    comments.append(f"source units {', '.join(units_used)}" + (f"; {ref_note}" if ref_note else ""))
    span = f"{min(reps)}" if min(reps) == max(reps) else f"{min(reps)}-{max(reps)}"
    comments.append(f"sigma: replicate standard error (replicates per curve {span})"
                    if spec.sigma_replicates and max(reps) > 1 else "sigma: no replicate term")
    if spec.sigma_absolute or spec.sigma_relative:
        comments[-1] += f", absolute {spec.sigma_absolute:g} (source units), relative {spec.sigma_relative:g}"
    ds = Dataset(np.array(cols["geometry"], int), np.array(cols["angle"]), np.array(cols["out"]),
                 np.array(cols["wl"]), np.array(cols["value"]), np.array(cols["sigma"]), comments,
                 np.array(cols["phi"]), np.array(cols["series"], dtype=object))
    notes.append(f"{len(placed)} curves -> {len(groups)} measured curves x {len(grid)} wavelengths "
                 f"({grid[0]:g}-{grid[-1]:g} nm) = {len(ds)} rows")
    if not resample:
        full = _increasing(placed[0].spectrum)[0]
        if len(full) != len(grid):
            notes.append(f"kept {len(grid)} of {len(full)} wavelengths (the model's range "
                         f"{MODEL_RANGE_NM[0]:g}-{MODEL_RANGE_NM[1]:g} nm)")
    if max(reps) > 1:
        notes.append(f"averaged replicates: {span} per curve")
    if not resample and len(grid) > 200:
        notes.append(f"{len(grid)} wavelengths per curve (the instrument's pixels): each costs forward-model time; "
                     f"a grid such as [wavelengths] step = 5 (--wavelengths 400:700:5) is usually enough")
    # the dataset's own checks (duplicates, ranges) on what will be written
    return parse_csv(ds.to_csv_text().splitlines(), "the imported dataset", units="fraction"), notes


def units_option(text: str | None) -> str | None:
    return None if text is None else check_units(text, "--units")
