"""The spectral grid on which colour is computed.

Default: 380-780 nm in 5 nm steps (81 samples). Why 5 nm: a thin film's reflectance
oscillates in wavelength with period ~ lambda^2 / (2 n d cos theta_1). For the thickest
films bsdflab presets use (optical thickness n d <= 2.4 um, e.g. 1200 nm at n = 2), the
shortest period is 380^2 / 4800 ~ 30 nm at 380 nm, so 5 nm gives >= 6 samples per period
(Nyquist needs 2). Thicker films need a finer grid: pass your own wavelengths.
"""
from __future__ import annotations

import numpy as np

from bsdflab.util.args import real_scalar

DEFAULT_STEP_NM = 5.0
DEFAULT_RANGE_NM = (380.0, 780.0)


def wavelength_grid(start: float = DEFAULT_RANGE_NM[0], end: float = DEFAULT_RANGE_NM[1],
                    step: float = DEFAULT_STEP_NM) -> np.ndarray:
    """Evenly spaced wavelengths in nm, both ends included."""
    start = real_scalar("start", start, 0.0, lo_open=True)
    end = real_scalar("end", end, start, lo_open=True)
    step = real_scalar("step", step, 0.0, lo_open=True)
    count = int(round((end - start) / step)) + 1
    return start + step * np.arange(count)


DEFAULT_WAVELENGTHS = wavelength_grid()
DEFAULT_WAVELENGTHS.setflags(write=False)
