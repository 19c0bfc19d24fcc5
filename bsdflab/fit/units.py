"""The units rule for reflectance values: percent is declared (and converted) or refused.

A file states its units (``units = "percent"`` or ``"fraction"`` in an import sidecar, the
``# units: percent`` comment of the long CSV, a ``[%]`` unit line in an instrument export).
Values whose units nobody stated are taken as fractions unless they look like percent:
a specular or total reflectance above ``PERCENT_THRESHOLD`` (no mirror or integrating-sphere
reading of a sample exceeds it as a fraction), or diffuse/brdf reflectance factors (all of
one series) whose median exceeds it (a gloss peak may, the bulk of a gonio set does not). Those are refused,
never silently accepted.
"""
from __future__ import annotations

import re

import numpy as np

UNITS = ("percent", "fraction")
PERCENT_THRESHOLD = 1.5
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


def percent_suspect(geometry, values) -> tuple[str, int] | None:
    """Why ``values`` (one series, undeclared units; ``geometry`` a name per value) look like
    percent, and the index of the value that shows it; None if they do not."""
    g = np.asarray(geometry, dtype=object)
    v = np.asarray(values, float)
    mirror = np.flatnonzero((g == "specular") | (g == "total"))
    if mirror.size:
        worst = int(mirror[np.argmax(v[mirror])])
        if v[worst] > PERCENT_THRESHOLD:
            return f"a {g[worst]} reflectance of {v[worst]:g} (> {PERCENT_THRESHOLD:g})", worst
    off = np.flatnonzero((g == "diffuse") | (g == "brdf"))
    if off.size and float(np.median(v[off])) > PERCENT_THRESHOLD:
        return (f"diffuse/brdf reflectance factors with median {float(np.median(v[off])):g} "
                f"(> {PERCENT_THRESHOLD:g})", int(off[np.argmax(v[off])]))
    return None


def refuse_percent(where: str, reason: str, how: str) -> ValueError:
    return ValueError(f"{where}: the values look like percent ({reason}); declare the units: "
                      f"{how} (percent is converted to fractions; \"fraction\" accepts the values as they are)")
