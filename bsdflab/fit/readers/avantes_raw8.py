"""Avantes AvaSoft 8 binary files (.raw8, .rfl8, .trm8, .rwd8: magic bytes ``AVS``) through
the ``avaread`` package.

Each channel block holds the wavelengths and the sample ("scope"), dark and reference counts
as float32; the value is (scope - dark) / (reference - dark), a fraction. Only single-channel
files are read (channels of a multi-channel spectrometer cover different ranges and are not
replicates). AvaSoft 7 binaries (.trm, .rfl, .raw without the ``AVS`` magic) have no kept
reader and are refused: export them as text (.ttt) from AvaSoft.
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.readers.base import Reader, Spectrum
from bsdflab.util.extras import require


class AvantesRaw8(Reader):
    name = "avantes-raw8"
    suffixes = (".raw8", ".rfl8", ".trm8", ".rwd8", ".trm")
    description = "Avantes AvaSoft 8 binary (.raw8, .rfl8, .trm8; via avaread)"

    def read(self, path: str, spec) -> list[Spectrum]:
        avaread = require("avaread.reader", "fit")
        with open(path, "rb") as f:
            magic = f.read(3)
        if magic != b"AVS":
            raise ValueError(f"{path}: byte 1: not an AvaSoft 8 file (no 'AVS' magic bytes; an AvaSoft 7 .trm/.rfl "
                             f"binary has no kept reader: export it as text, .ttt, from AvaSoft)")
        try:
            f8 = avaread.AVSFile(path)
        except (avaread.AvaReadException, ValueError, OSError, EOFError) as e:   # AvaReadException is a BaseException
            raise ValueError(f"{path}: cannot read the AvaSoft 8 file (truncated?): {e}") from None
        if len(f8.channels) != 1:
            raise ValueError(f"{path}: {len(f8.channels)} channels; only single-channel files are read "
                             f"(export each channel as text)")
        ch = f8.channels[0]
        wl, scope, dark, ref = (np.asarray(a, float) for a in (ch.wavelength, ch.scope, ch.dark, ch.ref))
        if len(wl) != len(ch) or len(wl) == 0:
            raise ValueError(f"{path}: the channel announces {len(ch)} pixels but holds {len(wl)}: truncated file")
        denom = ref - dark
        bad = np.flatnonzero(~(denom > 0) | ~np.isfinite(scope) | ~np.isfinite(wl))
        if bad.size:
            raise ValueError(f"{path}: pixel {bad[0] + 1} ({wl[bad[0]]:g} nm): reference - dark is {denom[bad[0]]:g} "
                             f"or a value is not finite: the reflectance cannot be computed there")
        return [Spectrum(wl, (scope - dark) / denom, path, "", f"{path}: channel 1", np.zeros(0, int), "fraction")]
