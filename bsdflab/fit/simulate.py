"""Synthetic data with known truth (``bsdflab fit simulate``).

Noise model: the stated uncertainty of row i is sigma_i = sqrt(absolute^2 + (relative y_i)^2)
with y_i the true model value, and the recorded value is y_i + noise_scale sigma_i z_i with
z_i independent standard normal draws from numpy's PCG64 seeded by ``seed``
(noise_scale = 1 unless the truth says otherwise: then the stated sigmas are wrong by that
factor, which a fit with a free noise_scale should find).
"""
from __future__ import annotations

import numpy as np

from bsdflab.fit.config import SimulationConfig
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.full_forward import forward_model
from bsdflab.fit.parameters import ALL_NAMES


def design(config: SimulationConfig) -> Dataset:
    """The rows the measurements describe (reflectance and sigma still zero)."""
    rows = []
    for m in config.measurements:
        for a, b, phi in m.angles:
            for wl in m.wavelengths_nm:
                rows.append((GEOMETRIES.index(m.geometry), a, b, float(wl), phi))
    arr = np.array(rows, dtype=float)
    zeros = np.zeros(len(arr))
    ds = Dataset(arr[:, 0].astype(int), arr[:, 1], arr[:, 2], arr[:, 3], zeros, zeros + 1.0, phi_deg=arr[:, 4])
    # the data file's own checks (range, duplicates, specular direction) apply to simulations too
    from bsdflab.fit.data import parse_csv

    return parse_csv(ds.to_csv_text().splitlines(), "simulated design")


def simulate(config: SimulationConfig, command: str = "") -> tuple[Dataset, np.ndarray]:
    """(noisy dataset, true model values)."""
    ds = design(config)
    model = forward_model(ds, config.model)
    y = model.evaluate(np.array([config.truth.get(n, np.nan) for n in ALL_NAMES]))
    if not np.all(np.isfinite(y)):
        raise ValueError("the truth lies outside the model's domain (the forward model gave NaN)")
    sigma = np.sqrt(config.absolute_noise ** 2 + (config.relative_noise * y) ** 2)
    rng = np.random.default_rng(config.seed)
    obs = y + config.truth["noise_scale"] * sigma * rng.standard_normal(len(y))
    truth = ", ".join(f"{k}={v:.10g}" for k, v in config.truth.items())
    comments = ["SYNTHETIC DATA (not a measurement), made by bsdflab fit simulate"
                + (f": {command}" if command else ""),
                f"truth: {truth}",
                f"noise: sigma = sqrt({config.absolute_noise:g}^2 + ({config.relative_noise:g} y)^2), "
                f"seed {config.seed}, numpy PCG64 standard normal"]
    return ds.with_reflectance(obs, sigma, comments), y


