"""Angles from column headers and file names.

Without a sidecar pattern, a name carries the angle of incidence when it is a number
(``15``, ``15.5``, ``15deg``, ``15°``), or holds one number written ``<n>deg`` / ``<n>°``
(``R_15deg``, ``scale-15deg-b``) or ``theta=<n>`` / ``angle=<n>`` / ``aoi=<n>`` (``=``
or ``:`` or nothing between). Any other text around it is a label (a replicate's name);
two such numbers in one name are ambiguous and refused.
"""
from __future__ import annotations

import os
import re

_NUMBER = r"(?P<angle>\d+(?:\.\d+)?)"    # no sign: a '-' before it is a separator
_WHOLE = re.compile(rf"^\s*{_NUMBER}\s*(?:deg|degrees|°)?\s*$", re.IGNORECASE)
_TOKENS = (re.compile(rf"(?<![A-Za-z0-9.])(?:theta|angle|aoi)\s*[=:]?\s*{_NUMBER}(?![0-9.])", re.IGNORECASE),
           re.compile(rf"(?<![0-9.]){_NUMBER}\s*(?:deg|degrees|°)(?![A-Za-z])", re.IGNORECASE))


def angle_from_name(name: str, where: str) -> float | None:
    """The angle a header or file stem names (module docstring), or None if it names none."""
    m = _WHOLE.match(name)
    if m:
        return float(m["angle"])
    found = {}
    for pattern in _TOKENS:
        for m in pattern.finditer(name):
            found[m.start("angle")] = float(m["angle"])
    values = sorted(set(found.values()))
    if len(values) > 1:
        raise ValueError(f"{where}: the name {name!r} holds several angles ({', '.join(f'{v:g}' for v in values)}); "
                         f"give the angle in the sidecar")
    return values[0] if values else None


def stem(path: str) -> str:
    return os.path.splitext(os.path.basename(path))[0]


def pattern_match(pattern: str, name: str, where: str) -> dict[str, str]:
    """The named groups of the sidecar's ``name_pattern`` in ``name``; ValueError if it does not match."""
    m = re.search(pattern, name)
    if m is None:
        raise ValueError(f"{where}: name_pattern {pattern!r} does not match {name!r}")
    return {k: v for k, v in m.groupdict().items() if v is not None}
