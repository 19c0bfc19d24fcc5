"""How to turn instrument files into the fit's dataset: the TOML sidecar and CLI options.

The sidecar (``<file>.toml`` beside the first file, or ``--sidecar``) declares what the files
do not say: the geometry, the angles of each column or file, the units, the reference
standard, the series, the uncertainty and the wavelength grid (keys: docs/fit_data.md,
"Importing instrument files"). CLI options override its top-level keys.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field, replace

import numpy as np
import tomllib

from bsdflab.fit.data import GEOMETRIES
from bsdflab.fit.units import check_units

TOP_KEYS = ("format", "geometry", "units", "angle_deg", "angles_deg", "angle_out_deg", "phi_deg", "series",
            "name_pattern", "wavelength_column", "delimiter", "decimal", "wavelengths", "sigma", "reference",
            "columns", "files")
CURVE_KEYS = ("angle_deg", "angle_out_deg", "phi_deg", "geometry", "series", "ignore")
SIGMA_KEYS = ("absolute", "relative", "replicates")
REFERENCE_KEYS = ("reflectance", "file", "units", "format")
GRID_KEYS = ("start", "stop", "step", "list")


@dataclass(frozen=True)
class Curve:
    """What the sidecar says about one column or file (None: not said)."""

    angle_deg: float | None = None
    angle_out_deg: float | None = None
    phi_deg: float | None = None
    geometry: str | None = None
    series: str | None = None
    ignore: bool = False


@dataclass(frozen=True)
class Reference:
    """The standard the values are relative to: a nominal reflectance or a spectrum file."""

    reflectance: float | None = None
    file: str | None = None
    units: str | None = None
    format: str | None = None


@dataclass(frozen=True)
class ImportSpec:
    format: str | None = None
    geometry: str | None = None
    units: str | None = None
    angle_deg: float | None = None
    angles_deg: tuple[float, ...] | None = None     # one per column (wide) or per file, in order
    angle_out_deg: float | None = None
    phi_deg: float | None = None
    series: str | None = None
    name_pattern: str | None = None
    wavelength_column: str | None = None
    delimiter: str | None = None
    decimal: str = "."
    wavelengths: np.ndarray | None = None            # the grid to resample onto (None: the files')
    sigma_absolute: float = 0.0
    sigma_relative: float = 0.0
    sigma_replicates: bool = True
    reference: Reference | None = None
    columns: dict[str, Curve] = field(default_factory=dict)
    files: dict[str, Curve] = field(default_factory=dict)
    source: str = "options"                          # the sidecar's path, for messages

    def with_options(self, **options) -> ImportSpec:
        """This spec with the CLI options that were given (None: not given) replacing its keys."""
        given = {k: v for k, v in options.items() if v is not None}
        return replace(self, **given)


def _real(where: str, key: str, value, lo: float = -math.inf, hi: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or not lo <= value <= hi:
        raise ValueError(f"{where}: {key} must be a number in [{lo:g}, {hi:g}], got {value!r}")
    return float(value)


def _text(where: str, key: str, value) -> str:
    if not isinstance(value, str):
        raise ValueError(f"{where}: {key} must be a string, got {value!r}")
    return value


def _keys(where: str, table, known) -> dict:
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table, got {table!r}")
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}; known: {', '.join(known)}")
    return table


def geometry(where: str, value) -> str:
    g = _text(where, "geometry", value).strip().lower()
    if g not in GEOMETRIES:
        raise ValueError(f"{where}: unknown geometry {value!r}; known: {', '.join(GEOMETRIES)}")
    return g


def name_pattern(where: str, value) -> str:
    text = _text(where, "name_pattern", value)
    try:
        compiled = re.compile(text)
    except re.error as e:
        raise ValueError(f"{where}: name_pattern is not a regular expression: {e}") from None
    if "angle" not in compiled.groupindex:
        raise ValueError(f"{where}: name_pattern must have a group named angle, e.g. '_(?P<angle>[0-9.]+)deg'")
    return text


def grid(where: str, value) -> np.ndarray:
    """A wavelength grid from {start, stop, step} or {list = [...]} (or a plain list)."""
    if isinstance(value, list):
        value = {"list": value}
    table = _keys(where, value, GRID_KEYS)
    if "list" in table:
        if set(table) != {"list"}:
            raise ValueError(f"{where}: give either list or start/stop/step")
        values = [_real(where, "list", v, 0.0) for v in table["list"]]
        if len(values) < 1 or np.any(np.diff(values) <= 0):
            raise ValueError(f"{where}: list must hold increasing wavelengths, got {table['list']!r}")
        return np.array(values)
    missing = [k for k in ("start", "stop", "step") if k not in table]
    if missing:
        raise ValueError(f"{where}: missing {', '.join(missing)} (or give list = [...])")
    start, stop = _real(where, "start", table["start"], 0.0), _real(where, "stop", table["stop"], 0.0)
    step = _real(where, "step", table["step"], 0.0)
    if step <= 0 or stop < start:
        raise ValueError(f"{where}: need step > 0 and stop >= start, got {start:g}:{stop:g}:{step:g}")
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    return start + step * np.arange(n)


def parse_grid_option(text: str) -> np.ndarray:
    """--wavelengths START:STOP:STEP or a comma list."""
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ValueError(f"--wavelengths must be START:STOP:STEP or a comma list, got {text!r}")
        try:
            start, stop, step = (float(p) for p in parts)
        except ValueError:
            raise ValueError(f"--wavelengths must be START:STOP:STEP or a comma list, got {text!r}") from None
        return grid("--wavelengths", {"start": start, "stop": stop, "step": step})
    return grid("--wavelengths", {"list": [float_option("--wavelengths", p) for p in text.split(",")]})


def float_option(option: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{option} must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{option} must be finite, got {text!r}")
    return value


def _curve(where: str, table) -> Curve:
    t = _keys(where, table, CURVE_KEYS)
    ignore = t.get("ignore", False)
    if not isinstance(ignore, bool):
        raise ValueError(f"{where}: ignore must be true or false, got {ignore!r}")
    return Curve(
        angle_deg=_real(where, "angle_deg", t["angle_deg"], 0.0, 90.0) if "angle_deg" in t else None,
        angle_out_deg=_real(where, "angle_out_deg", t["angle_out_deg"], -90.0, 90.0) if "angle_out_deg" in t else None,
        phi_deg=_real(where, "phi_deg", t["phi_deg"], -180.0, 180.0) if "phi_deg" in t else None,
        geometry=geometry(where, t["geometry"]) if "geometry" in t else None,
        series=_text(where, "series", t["series"]) if "series" in t else None,
        ignore=ignore)


def _text_keys(t: dict, source: str) -> dict:
    """The top-level strings: format, wavelength_column, delimiter, series and decimal."""
    kw: dict = {}
    for key in ("format", "wavelength_column", "delimiter", "series"):
        if key in t:
            kw[key] = _text(source, key, t[key])
    if "decimal" in t:
        kw["decimal"] = _text(source, "decimal", t["decimal"])
        if kw["decimal"] not in (".", ","):
            raise ValueError(f"{source}: decimal must be \".\" or \",\", got {t['decimal']!r}")
    return kw


def _angle_keys(t: dict, source: str) -> dict:
    """The top-level angles: angle_deg, angles_deg, angle_out_deg and phi_deg."""
    kw: dict = {}
    if "angle_deg" in t:
        kw["angle_deg"] = _real(source, "angle_deg", t["angle_deg"], 0.0, 90.0)
    if "angles_deg" in t:
        if not isinstance(t["angles_deg"], list):
            raise ValueError(f"{source}: angles_deg must be a list, got {t['angles_deg']!r}")
        kw["angles_deg"] = tuple(_real(source, "angles_deg", a, 0.0, 90.0) for a in t["angles_deg"])
    if "angle_out_deg" in t:
        kw["angle_out_deg"] = _real(source, "angle_out_deg", t["angle_out_deg"], -90.0, 90.0)
    if "phi_deg" in t:
        kw["phi_deg"] = _real(source, "phi_deg", t["phi_deg"], -180.0, 180.0)
    return kw


def _sigma(source: str, table) -> dict:
    """The [sigma] table as ImportSpec's sigma_* keys."""
    where = f"{source}: [sigma]"
    s = _keys(where, table, SIGMA_KEYS)
    kw: dict = {}
    if "absolute" in s:
        kw["sigma_absolute"] = _real(where, "absolute", s["absolute"], 0.0)
    if "relative" in s:
        kw["sigma_relative"] = _real(where, "relative", s["relative"], 0.0)
    if "replicates" in s:
        if not isinstance(s["replicates"], bool):
            raise ValueError(f"{source}: [sigma] replicates must be true or false, got {s['replicates']!r}")
        kw["sigma_replicates"] = s["replicates"]
    return kw


def _reference(source: str, table) -> Reference:
    """The [reference] table; a spectrum file's path is relative to the sidecar's folder."""
    where = f"{source}: [reference]"
    r = _keys(where, table, REFERENCE_KEYS)
    if ("reflectance" in r) == ("file" in r):
        raise ValueError(f"{where}: give either reflectance (the standard's nominal value) or file "
                         f"(its reflectance spectrum)")
    ref = Reference(
        reflectance=_real(where, "reflectance", r["reflectance"], 0.0, 100.0) if "reflectance" in r else None,
        file=_text(where, "file", r["file"]) if "file" in r else None,
        units=check_units(r["units"], f"{where}: units") if "units" in r else None,
        format=_text(where, "format", r["format"]) if "format" in r else None)
    if ref.reflectance is not None and ref.reflectance > 1.5 and ref.units != "percent":
        raise ValueError(f"{where}: reflectance {r['reflectance']!r} looks like percent; "
                         f"write it as a fraction or add units = \"percent\"")
    if ref.file is not None:
        base = os.path.dirname(source) if os.path.isfile(source) else ""
        ref = replace(ref, file=os.path.join(base, ref.file))
    return ref


def _curves(source: str, key: str, table) -> dict[str, Curve]:
    """The [columns] or [files] table: one Curve per name."""
    if not isinstance(table, dict):
        raise ValueError(f"{source}: [{key}] must be a table of tables")
    return {name: _curve(f"{source}: [{key}.\"{name}\"]", v) for name, v in table.items()}


def parse_spec(table: dict, source: str) -> ImportSpec:
    """An ImportSpec from a sidecar's parsed TOML (``source`` names it in messages)."""
    t = _keys(source, table, TOP_KEYS)
    kw: dict = {"source": source, **_text_keys(t, source)}
    if "geometry" in t:
        kw["geometry"] = geometry(source, t["geometry"])
    if "units" in t:
        kw["units"] = check_units(t["units"], f"{source}: units")
    kw.update(_angle_keys(t, source))
    if "name_pattern" in t:
        kw["name_pattern"] = name_pattern(source, t["name_pattern"])
    if "wavelengths" in t:
        kw["wavelengths"] = grid(f"{source}: [wavelengths]", t["wavelengths"])
    if "sigma" in t:
        kw.update(_sigma(source, t["sigma"]))
    if "reference" in t:
        kw["reference"] = _reference(source, t["reference"])
    for key in ("columns", "files"):
        if key in t:
            kw[key] = _curves(source, key, t[key])
    return ImportSpec(**kw)


def load_spec(path: str | os.PathLike) -> ImportSpec:
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            table = tomllib.load(f)
    except OSError as e:
        raise ValueError(f"cannot read sidecar {path}: {e}") from None
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{path}: not valid TOML: {e}") from None
    return parse_spec(table, path)
