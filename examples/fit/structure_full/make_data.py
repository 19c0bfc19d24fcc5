"""Make the SYNTHETIC data of the full-model structure example (not a measurement):

    python examples/fit/structure_full/make_data.py [--out data.csv]

The truth's Layered model is written out here by hand (not by the fit's FullStructure), pi f
is estimated by Position-Free Monte Carlo (``Layered.estimate``, not the adding-doubling
solver the fit uses), and the instrument (scale) and Gaussian noise are applied in numpy:
neither the fit's model builder nor its solver nor its emulator made these numbers, so
recovering the truth is not an inverse crime. sigma = sqrt(PFMC standard error^2 +
(relative y)^2).
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from bsdflab import presets
from bsdflab.bsdfs import from_dict
from bsdflab.fit.data import GEOMETRIES, Dataset

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

HERE = os.path.dirname(os.path.abspath(__file__))


def truth_model(t: dict, samples: int = 256) -> dict:
    """air | guanine 400 nm | keratin (at 550 nm) | eumelanin slab 4 um | Lambertian base,
    rough GGX top (examples/fit/structure_full/structure.toml), with the truth's values."""
    wl = np.arange(350.0, 1002.5, 5.0)
    # eumelanin: k = 0.56 exp(-lambda / 270 nm) (Stavenga et al. 2015); sigma_a ~ 4 pi k / lambda
    shape = np.exp(-wl / 270.0) / wl / (np.exp(-550.0 / 270.0) / 550.0)
    keratin = presets.KERATIN_CAUCHY["A"] + presets.KERATIN_CAUCHY["B"] / 550.0**2
    return {
        "type": "layered",
        "samples": samples,
        "interfaces": [
            {
                "type": "roughdielectric",
                "int_ior": keratin,
                "ext_ior": presets.AIR_IOR,
                "alpha": t["roughness"],
                "distribution": "ggx",
                "film": [{"material": presets.GUANINE_IOR, "thickness_nm": 400.0}],
            }
        ],
        "slabs": [
            {
                "thickness_um": 4.0,
                "sigma_s": t["sigma_s"],
                "phase": {"type": "hg", "g": 0.6},
                "sigma_a": {"type": "tabulated", "wavelengths": wl.tolist(), "values": (0.4 * shape).tolist()},
            }
        ],
        "base": {"type": "diffuse", "reflectance": t["base_albedo"]},
    }


def design(triples, wavelengths) -> Dataset:
    a = np.array([(*p, w) for w in wavelengths for p in triples], float)
    n = len(a)
    return Dataset(
        np.full(n, GEOMETRIES.index("brdf")), a[:, 0], a[:, 1], a[:, 3], np.zeros(n), np.ones(n), phi_deg=a[:, 2]
    )


def directions(ds: Dataset) -> tuple[np.ndarray, np.ndarray]:
    """(detector, source) unit vectors: source in the x-z plane at -x, phi from the mirror side."""
    ti, to, ph = (np.radians(x) for x in (ds.angle_deg, ds.angle_out_deg, ds.phi_deg))
    source = np.column_stack([-np.sin(ti), np.zeros_like(ti), np.cos(ti)])
    detector = np.column_stack([np.sin(to) * np.cos(ph), np.sin(to) * np.sin(ph), np.cos(to)])
    return detector, source


def make(truth_path: str = os.path.join(HERE, "truth.toml")) -> Dataset:
    with open(truth_path, "rb") as f:
        cfg = tomllib.load(f)
    t, noise, d = cfg["truth"], cfg["noise"], cfg["design"]
    ds = design(d["angle_triples_deg"], d["wavelengths_nm"])
    model = from_dict(truth_model(t))
    det, src = directions(ds)
    y = np.empty(len(ds))
    se = np.empty(len(ds))
    for w in np.unique(ds.wavelength_nm):
        rows = ds.wavelength_nm == w
        e = model.estimate(det[rows], src[rows], wavelengths=[w], samples=noise["walks"], seed=noise["seed"])
        y[rows] = np.pi * e.value[:, 0] / src[rows, 2]
        se[rows] = np.pi * e.stderr[:, 0] / src[rows, 2]
    y *= t["scale"]
    se *= t["scale"]
    sigma = np.sqrt(se**2 + (noise["relative"] * y) ** 2)
    rng = np.random.default_rng(noise["seed"])
    values = y + noise["relative"] * y * rng.standard_normal(len(y))
    comments = [
        "SYNTHETIC DATA (not a measurement): PFMC (Layered.estimate) of the truth in truth.toml, "
        "made by examples/fit/structure_full/make_data.py",
        "truth: " + ", ".join(f"{k}={v:g}" for k, v in t.items()),
        f"noise: sigma = sqrt(PFMC stderr^2 + ({noise['relative']:g} y)^2), seed {noise['seed']}, "
        f"{noise['walks']} walks per geometry",
    ]
    return ds.with_reflectance(values, sigma, comments)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(HERE, "data.csv"))
    args = ap.parse_args()
    text = make().to_csv_text()
    tmp = args.out + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, args.out)
    print(f"wrote {args.out}")
