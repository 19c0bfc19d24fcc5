"""JCAMP-DX (.jdx, .dx) through the ``jcamp`` package (McDonnell & Hastings' format,
Appl. Spectrosc. 1988; uncompressed and compressed XYDATA, XYPOINTS).

X units NANOMETERS, MICROMETERS or 1/CM (converted to nm); Y units naming percent
("%", "PERCENT") state percent, REFLECTANCE/TRANSMITTANCE/ABSORBANCE-free fractions state
nothing (the units rule decides). ``jcamp`` skips values it cannot parse without saying so,
so the count it returns is checked against ##NPOINTS and the data block's lines are named
when they differ.
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.readers.base import Reader, Spectrum
from bsdflab.fit.readers.text import read_lines
from bsdflab.util.extras import require


def _block(lines: list[str]) -> tuple[int, int]:
    start = next((i for i, ln in enumerate(lines) if ln.upper().startswith(("##XYDATA", "##XYPOINTS"))), None)
    if start is None:
        return 0, 0
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("##")), len(lines))
    return start + 1, end


class JcampDX(Reader):
    name = "jcamp"
    suffixes = (".jdx", ".dx", ".jcamp")
    description = "JCAMP-DX spectrum (via the jcamp package)"

    def read(self, path: str, spec) -> list[Spectrum]:
        jcamp = require("jcamp", "fit")
        lines = read_lines(path)
        start, end = _block(lines)
        if not start:
            raise ValueError(f"{path}: no ##XYDATA or ##XYPOINTS block: not a JCAMP-DX spectrum")
        try:
            with open(path, encoding="utf-8", errors="replace") as f:
                d = jcamp.read(f)
        except (ValueError, IndexError, KeyError) as e:
            raise ValueError(f"{path}: cannot parse JCAMP-DX (data block lines {start + 1}-{end}): {e}") from None
        x, y = np.asarray(d.get("x", []), float), np.asarray(d.get("y", []), float)
        declared = d.get("npoints")
        if len(x) == 0 or len(x) != len(y) or (declared is not None and int(declared) != len(x)):
            raise ValueError(f"{path}: lines {start + 1}-{end}: the data block gives {len(x)} points but ##NPOINTS "
                             f"says {declared}: a value there is not a number")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise ValueError(f"{path}: lines {start + 1}-{end}: non-finite values in the data block")
        xunits = str(d.get("xunits", "NANOMETERS")).strip().upper()
        if xunits in ("NANOMETERS", "NM"):
            wl = x
        elif xunits in ("MICROMETERS", "UM", "MICRONS"):
            wl = 1000.0 * x
        elif xunits in ("1/CM", "CM-1", "CM^-1"):
            wl = 1e7 / x
        else:
            raise ValueError(f"{path}: ##XUNITS={d.get('xunits')}: known units are NANOMETERS, MICROMETERS, 1/CM")
        yunits = str(d.get("yunits", "")).strip().upper()
        stated = "percent" if ("%" in yunits or "PERCENT" in yunits) else None
        order = np.argsort(wl, kind="stable")
        return [Spectrum(wl[order], y[order], path, "", f"{path}: ##XYDATA", np.zeros(0, int), stated)]
