"""How far Mitsuba's spectral estimate can sit from ours for the same spectral scene.

    python bench/spectral_mitsuba_residual.py

For paths of one to three bounces on the cross-check scenes' spectra, prints the largest
relative difference over RGB channels between our pixel value (the 5 nm sum through W)
and the value Mitsuba's estimator converges to (reference/mitsuba_spectral.py
``residual``): with the step mapping the cross-check uses, and with the obvious
alternative (linear spectra, D65 in the emitter, Mitsuba's own CIE film) for comparison.
No timing: the numbers do not depend on the machine.
"""
from __future__ import annotations

import numpy as np

from bsdflab import Conductor
from bsdflab.reference.mitsuba_spectral import residual
from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum


def paths():
    wl = DEFAULT_WAVELENGTHS
    spheres = Spectrum.rgb([0.7, 0.25, 0.15]).at(wl)       # basic-materials' diffuse sphere
    ball = Spectrum.rgb([0.8, 0.3, 0.1]).at(wl)             # sphere-on-floor's red ball
    copper = {t: Conductor("Cu").sample(np.array([[np.sin(np.radians(t)), 0.0, np.cos(np.radians(t))]]),
                                        wavelengths=wl, seed=0).weight[0] for t in (0, 60)}
    sky, lamp = (0.6, 0.7, 0.9), (4.0, 4.0, 4.0)
    return [("grey lamp seen directly", [], lamp), ("coloured sky seen directly", [], sky),
            ("diffuse sphere, 1 bounce, lamp", [spheres], lamp),
            ("red ball, 2 bounces, sky", [ball, ball], sky), ("red ball, 3 bounces, sky", [ball] * 3, sky),
            ("copper 0 and 60 deg, sky", [copper[0], copper[60]], sky),
            ("copper then red ball, lamp", [copper[0], ball], lamp)]


def main() -> None:
    print(f"{'path':34s} {'step mapping':>13s} {'linear + CIE film':>18s}")
    for name, spectra, emission in paths():
        print(f"{name:34s} {residual(spectra, emission):13.1e} {residual(spectra, emission, 'continuous'):18.1e}")


if __name__ == "__main__":
    main()
