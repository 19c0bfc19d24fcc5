"""Make the SYNTHETIC wide-form example (not a measurement): specular reflectance at 12 angles
(15-70 deg) x 71 wavelengths (350-700 nm), two replicate scans per angle, in percent relative
to a white diffuse standard of reflectance 0.99, as a lab's spreadsheet keeps it.

    python examples/fit/wide/make_wide.py      # writes examples/fit/wide/angles.csv
"""
from __future__ import annotations

import os

import numpy as np

from bsdflab.fit.config import SimulationConfig
from bsdflab.fit.simulate import simulate

HERE = os.path.dirname(os.path.abspath(__file__))
ANGLES = list(range(15, 71, 5))
STANDARD = 0.99          # the white standard's nominal reflectance (as in angles.csv.toml)
TRUTH = {"film_thickness_nm": 430.0, "film_thickness_spread_nm": 12.0, "film_index_A": 1.83,
         "sigma_a_550": 0.4, "base_albedo": 0.3}


def main() -> None:
    scans = []
    for seed in (2024, 2025):        # two replicate scans: the same truth, independent noise
        config = SimulationConfig.parse({
            "truth": TRUTH, "noise": {"relative": 0.02, "absolute": 0.001, "seed": seed},
            "measurement": [{"geometry": "specular", "angles_deg": ANGLES,
                             "wavelengths_nm": {"start": 350, "stop": 700, "step": 5}}]})
        ds, _ = simulate(config)
        scans.append(ds)
    wl = np.unique(scans[0].wavelength_nm)
    truth = ", ".join(f"{k}={v:g}" for k, v in TRUTH.items())
    lines = ["# SYNTHETIC DATA (not a measurement), made by examples/fit/wide/make_wide.py",
             f"# truth: {truth}",
             "# specular reflectance in percent relative to a white standard of reflectance 0.99",
             ",".join(["wavelength_nm"] + [f"R_{a}deg_{r}" for a in ANGLES for r in "ab"])]
    for w in wl:
        cells = [f"{w:g}"]
        for a in ANGLES:
            for ds in scans:
                i = np.flatnonzero((ds.angle_deg == a) & (ds.wavelength_nm == w))[0]
                cells.append(f"{100.0 * ds.reflectance[i] / STANDARD:.3f}")
        lines.append(",".join(cells))
    with open(os.path.join(HERE, "angles.csv"), "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
