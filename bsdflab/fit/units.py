"""The units rule for reflectance values: percent is declared (and converted) or refused.

A file states its units (``units = "percent"`` or ``"fraction"`` in an import sidecar, the
``# units: percent`` comment of the long CSV, a ``[%]`` unit line in an instrument export).
Values whose units nobody stated are taken as fractions unless they look like percent:
a specular or total reflectance above ``PERCENT_THRESHOLD`` (no mirror or integrating-sphere
reading of a sample exceeds it as a fraction), or diffuse/brdf reflectance factors (all of
one series, those within ``NEAR_MIRROR_DEG`` of the mirror direction left out: a gloss peak
may exceed it) whose median exceeds it. Those are refused,
never silently accepted.
"""
from __future__ import annotations

import re

import numpy as np

UNITS = ("percent", "fraction")
PERCENT_THRESHOLD = 1.5
NEAR_MIRROR_DEG = 15.0      # gloss peaks left out of the diffuse/brdf median
_COMMENT = re.compile(r"^units\s*[:=]\s*\"?(?P<units>[A-Za-z]+)\"?\s*$", re.IGNORECASE)


def check_units(name: str, where: str) -> str:
    """``name`` as one of UNITS; ValueError naming ``where`` otherwise."""
    text = str(name).strip().lower()
    if text in ("%", "percent", "pct"):
        return "percent"
    if text in ("fraction", "1", "ratio"):
        return "fraction"
    raise ValueError(f"{where}: units must be \"percent\" or \"fraction\", got {name!r}")


def units_comment(comment: str, where: str) -> str | None:
    """The units a ``units: percent`` comment declares, or None if the comment is another one."""
    m = _COMMENT.match(comment.strip())
    return check_units(m["units"], where) if m else None


def scale(units: str) -> float:
    """The factor that turns values in ``units`` into fractions."""
    return 0.01 if units == "percent" else 1.0


def near_mirror(geometry, angle_deg, angle_out_deg, phi_deg) -> np.ndarray:
    """Rows whose detector lies within NEAR_MIRROR_DEG of the mirror direction (a gloss peak:
    a reflectance factor there may exceed 1 as a fraction). Diffuse rows are in the plane of
    incidence, angle_out_deg > 0 on the mirror side; brdf rows have phi_deg = 0 there."""
    g = np.asarray(geometry, dtype=object)
    ti, to = np.radians(np.asarray(angle_deg, float)), np.radians(np.asarray(angle_out_deg, float))
    phi = np.radians(np.where(g == "diffuse", np.where(to >= 0, 0.0, 180.0), np.asarray(phi_deg, float)))
    cos = np.cos(ti) * np.cos(np.abs(to)) + np.sin(ti) * np.sin(np.abs(to)) * np.cos(phi)
    off = (g == "diffuse") | (g == "brdf")
    with np.errstate(invalid="ignore"):
        return off & (cos > np.cos(np.radians(NEAR_MIRROR_DEG)))


def percent_suspect(geometry, values, near=None) -> tuple[str, int] | None:
    """Why ``values`` (one series, undeclared units; ``geometry`` a name per value) look like
    percent, and the index of the value that shows it; None if they do not. ``near``: rows
    near the mirror direction (near_mirror), left out of the diffuse/brdf median."""
    g = np.asarray(geometry, dtype=object)
    v = np.asarray(values, float)
    mirror = np.flatnonzero((g == "specular") | (g == "total"))
    if mirror.size:
        worst = int(mirror[np.argmax(v[mirror])])
        if v[worst] > PERCENT_THRESHOLD:
            return f"a {g[worst]} reflectance of {v[worst]:g} (> {PERCENT_THRESHOLD:g})", worst
    keep = ((g == "diffuse") | (g == "brdf")) & (True if near is None else ~np.asarray(near, bool))
    off = np.flatnonzero(keep)
    if off.size and float(np.median(v[off])) > PERCENT_THRESHOLD:
        return (f"off-specular diffuse/brdf reflectance factors with median {float(np.median(v[off])):g} "
                f"(> {PERCENT_THRESHOLD:g})", int(off[np.argmax(v[off])]))
    return None


def refuse_percent(where: str, reason: str, how: str) -> ValueError:
    return ValueError(f"{where}: the values look like percent ({reason}); declare the units: "
                      f"{how} (percent is converted to fractions; \"fraction\" accepts the values as they are)")
