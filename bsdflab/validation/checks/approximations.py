"""How wrong are the industry's thin-film approximations? (reference/approximations)

Two checks that the comparison models reproduce their specifications' own behaviour, then
two studies (kind "study": numbers, no pass/fail limit) of their CIEDE2000 error against
bsdflab's exact spectral film: the snake's film (guanine 1.83 on keratin 1.5515, outside
air) over angle x thickness, and the appearance grid of Padrón-Griffe et al. 2023 (guanine on interior
index 1.0 or 2.0, thicknesses 300 / 600 / 1200 nm).
"""
from __future__ import annotations

import numpy as np

from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import REGISTRY, Outcome, effort

SNAKE = (1.000277, 1.83, 1.5515)  # air | guanine | keratin at 550 nm (bsdflab.presets)
GRID_THICKNESSES = (300.0, 600.0, 1200.0)
GRID_INTERIORS = (1.0, 2.0)
STUDY_EFFORT = effort({"angles": 19, "thicknesses": 61}, {"angles": 46, "thicknesses": 151},
                      {"angles": 90, "thicknesses": 301})


@REGISTRY.check(name="films/approximations/specifications", family="films",
                title="The comparison models reproduce their specifications' stated behaviour",
                model="reference.approximations: Belcour-Barla (MaterialX), Cycles, glTF iridescence, "
                      "Padrón-Griffe et al. 2023's double-phase film",
                reference="the specifications: no film effect when film index = outer index; "
                          "Belcour-Barla's series is the exact Airy sum (exact sensitivities); "
                          "the paper's Gaussian fit reproduces exact colour at normal incidence",
                statistic="largest violation, in units of its tolerance (<= 1 passes)",
                tolerance="(a) film index = outer index: every model equals its bare-interface value "
                          "(the same model with d = 0) to 1e-9 at 0, 30 and 60 deg -- glTF only at normal "
                          "incidence and within its R12 R23 >= 1e-5 clamp, twice 2 (1e-5^0.5 + 1e-5) max|S| for a "
                          "difference, because Schlick's F(F0 = 0) = (1 - cos)^5 keeps its film visible off normal "
                          "(reported); (b) Belcour-Barla with exact sensitivities and 60 terms equals the exact "
                          "spectral sRGB to 1e-6 (series truncation (R12 R23)^30 < 1e-20 and a 1 nm grid on both "
                          "sides); (c) with the "
                          "paper's Gaussian fit and 2 terms, in the paper's own space (XYZ, illuminant E), "
                          "Delta E00 <= 2 (a JND) against the exact spectral XYZ at normal incidence for "
                          "films up to 300 nm (the paper's examples, e.g. its 290 nm leather) -- its claim of "
                          "RGB results consistent with spectral rendering. We found no numeric error bound "
                          "stated in the paper, so the JND stands in; beyond 300 nm the fit errs more (up "
                          "to ~3.5 at 700 nm for the snake's film, reported in the study)",
                effort=effort({}, {}), seed=0)
def _specifications(ctx):
    from bsdflab.reference.approximations import (
        MODELS,
        XYZ_TO_SRGB,
        belcour_barla_rgb,
        belcour_barla_xyz,
        xyz_sensitivity_gaussian,
    )
    from bsdflab.reference.approximations.study import delta_e00_xyz_e, exact_rgb, exact_xyz_illuminant_e

    d = np.linspace(0.0, 1500.0, 31)
    cos = np.cos(np.radians(np.array([0.0, 30.0, 60.0])))[:, None]
    ratios, residues = {}, {}
    for name, fn in MODELS.items():
        same = fn(1.33, 1.33, 1.6, d[None, :], cos)
        bare = fn(1.33, 1.33, 1.6, 0.0 * d[None, :], cos)
        residue = np.abs(same - bare).max(axis=(1, 2))   # per angle
        residues[name] = dict(zip(("0 deg", "30 deg", "60 deg"), residue))
        if name.startswith("glTF"):
            # glTF clamps R12 R23 >= 1e-5, so sum_m 2 |C_m| |S| <= 2 (1e-5^0.5 + 1e-5) max|S|
            # remains; and Schlick's F(F0 = 0) = (1 - cos)^5 is not 0 off normal incidence,
            # so the spec's film only vanishes at normal incidence (reported as a residue).
            s_max = float(np.abs(xyz_sensitivity_gaussian(np.linspace(0, 6000, 601), 0.0) @ XYZ_TO_SRGB.T).max())
            limit = 2.0 * 2.0 * (1e-5 ** 0.5 + 1e-5) * s_max  # a difference of two such values
            ratios[f"(a) {name}, normal incidence"] = float(residue[0]) / limit
        else:
            ratios[f"(a) {name}"] = float(residue.max()) / 1e-9
    n1, n2, n3 = SNAKE
    series = belcour_barla_rgb(n1, n2, n3, d[None, :], cos, terms=60, sensitivity="exact")
    ratios["(b) series = exact"] = float(np.max(np.abs(series - exact_rgb(n1, n2, n3, d[None, :], cos)))) / 1e-6
    thin = np.linspace(0.0, 300.0, 31)
    de = delta_e00_xyz_e(belcour_barla_xyz(n1, n2, n3, thin, 1.0), exact_xyz_illuminant_e(n1, n2, n3, thin, 1.0))
    ratios["(c) Gaussian fit at normal incidence, <= 300 nm"] = float(de.max()) / 2.0
    worst = max(ratios.values())
    return Outcome(worst <= 1.0, worst, 1.0, "<=", "; ".join(f"{k}: {v:.3g}" for k, v in ratios.items()),
                   {"violation_over_tolerance": ratios,
                    "max_delta_e00_xyz_e_normal_incidence_le_300nm": float(de.max()),
                    "film_effect_at_equal_index_max_abs_rgb": residues})


def _map_figure(ctx, study, title):
    names = list(study.delta_e)
    fig, axes = new_figure(4.2 * len(names), 3.4, cols=len(names))
    extent = (study.thicknesses_nm[0], study.thicknesses_nm[-1], study.angles_deg[0], study.angles_deg[-1])
    for ax, name in zip(axes, names):
        im = ax.imshow(study.delta_e[name], origin="lower", aspect="auto", extent=extent, cmap="magma",
                       vmin=0, vmax=max(10.0, float(np.percentile(study.delta_e[name], 99))))
        ax.contour(study.thicknesses_nm, study.angles_deg, study.delta_e[name], levels=[2.0], colors="c",
                   linewidths=0.8)
        ax.set_title(f"{name}\n{100 * study.fraction_over(name):.0f}% over dE00 = 2", fontsize=8)
        ax.set_xlabel("film thickness (nm)")
        ax.set_ylabel("angle of incidence (deg)")
        fig.colorbar(im, ax=ax, fraction=0.046, pad=0.03)
    ctx.figure(fig, f"{title}: CIEDE2000 against the exact spectral film (cyan: dE00 = 2)")


def _swatch_figure(ctx, study, title):
    """Colour strips (normal incidence and 60 deg) over thickness: exact above each model."""
    fig, axes = new_figure(10.0, 3.6, rows=2)
    rows = [("exact", study.exact)] + list(study.models.items())
    for ax, angle in zip(axes, (0.0, 60.0)):
        i = int(np.argmin(np.abs(study.angles_deg - angle)))
        strip = np.stack([rgb[i] for _, rgb in rows])
        scale = 1.0 / max(float(np.percentile(study.exact[i], 99)), 1e-6)
        img = np.clip(strip * scale, 0, 1) ** (1 / 2.2)
        ax.imshow(img, aspect="auto", interpolation="nearest",
                  extent=(study.thicknesses_nm[0], study.thicknesses_nm[-1], len(rows), 0))
        ax.set_yticks(np.arange(len(rows)) + 0.5)
        ax.set_yticklabels([n.split(" (")[0] for n, _ in rows], fontsize=7)
        ax.set_title(f"{title}, {study.angles_deg[i]:.0f} deg (exposure x{scale:.1f}, gamma 2.2)", fontsize=8)
    axes[-1].set_xlabel("film thickness (nm)")
    ctx.figure(fig, f"{title}: reflected colour, exact spectral film against each approximation")


def _spectra_figure(ctx, n_outer, n_film, n_base, points, title):
    from bsdflab.reference.approximations import double_phase_reflectance
    from bsdflab.reference.approximations.study import SPECTRAL_GRID_NM, exact_spectrum

    fig, axes = new_figure(4.0 * len(points), 3.0, cols=len(points))
    for ax, (d, angle) in zip(axes, points):
        c = np.cos(np.radians(angle))
        ax.plot(SPECTRAL_GRID_NM, exact_spectrum(n_outer, n_film, n_base, d, c), "k", lw=1, label="exact")
        ax.plot(SPECTRAL_GRID_NM, double_phase_reflectance(n_outer, n_film, n_base, d, SPECTRAL_GRID_NM, c),
                "r", lw=0.8, alpha=0.7, label="double-phase formula")
        ax.plot([650, 510, 475], double_phase_reflectance(n_outer, n_film, n_base, d, np.array([650, 510, 475.0]), c),
                "ro", ms=4, label="its 3 samples")
        ax.set_title(f"{d:g} nm, {angle:g} deg", fontsize=8)
        ax.set_xlabel("wavelength (nm)")
        ax.legend(fontsize=6)
    axes[0].set_ylabel("reflectance")
    ctx.figure(fig, f"{title}: spectra at a few points (the RGB models have no spectrum; the double-phase "
                    "formula's is shown with its three samples)")


def _study_outcome(studies) -> Outcome:
    details = {s.label: s.summary() for s in studies}
    worst = max(v["fraction_over_jnd"] for s in details.values() for v in s.values())
    lines = [f"{label}: " + ", ".join(f"{n.split(' (')[0]} {100 * v['fraction_over_jnd']:.0f}% > JND "
                                      f"(median {v['median_delta_e00']:.1f})" for n, v in s.items())
             for label, s in details.items()]
    return Outcome(True, worst, 2.0, "fraction over dE00", " | ".join(lines), details)


@REGISTRY.check(name="films/approximations/snake", family="films", kind="study",
                title="Thin-film approximations on the snake's film",
                model="Belcour-Barla as MaterialX computes it (MaterialX / OpenPBR / Standard Surface), "
                      "Cycles' thin film (Blender >= 4.2, from its source, held to bpy renders), glTF "
                      "KHR_materials_iridescence, the Padrón-Griffe et al. 2023's double-phase film",
                reference="bsdflab's exact spectral film (guanine 1.83 on keratin 1.5515, air outside), "
                          "D65, CIE 1931 2 deg, linear sRGB, CIEDE2000 (colour-science)",
                statistic="largest fraction of the angle x thickness map with dE00 > 2",
                tolerance="none: a study (dE00 = 2 marks a just-noticeable difference)",
                effort=STUDY_EFFORT, seed=0)
def _snake_study(ctx):
    from bsdflab.reference.approximations.study import film_study

    angles = np.linspace(0.0, 85.0, int(ctx.effort["angles"]))
    d = np.linspace(0.0, 1500.0, int(ctx.effort["thicknesses"]))
    study = film_study("snake film", *SNAKE, angles, d)
    _map_figure(ctx, study, "snake film (guanine on keratin)")
    _swatch_figure(ctx, study, "snake film")
    _spectra_figure(ctx, *SNAKE, [(400.0, 0.0), (400.0, 60.0), (1200.0, 30.0)], "snake film")
    return _study_outcome([study])


@REGISTRY.check(name="films/approximations/appearance-grid", family="films", kind="study",
                title="Thin-film approximations on the paper's appearance grid",
                model="as films/approximations/snake",
                reference="bsdflab's exact spectral film: guanine 1.83 on interior index 1.0 or 2.0, "
                          "outside 1.0 (bsdflab.scenes.appearance_grid)",
                statistic="largest fraction of the angle x thickness map with dE00 > 2",
                tolerance="none: a study", effort=STUDY_EFFORT, seed=0)
def _grid_study(ctx):
    from bsdflab.reference.approximations.study import film_study

    angles = np.linspace(0.0, 85.0, int(ctx.effort["angles"]))
    d = np.linspace(0.0, 1500.0, int(ctx.effort["thicknesses"]))
    studies = []
    cells = {}
    for n in GRID_INTERIORS:
        s = film_study(f"interior {n:g}", 1.0, 1.83, n, angles, d)
        studies.append(s)
        _map_figure(ctx, s, f"appearance grid, interior index {n:g}")
        cell = film_study(f"interior {n:g} cells", 1.0, 1.83, n, angles, np.array(GRID_THICKNESSES))
        for k, t in enumerate(GRID_THICKNESSES):
            cells[f"{t:g} nm, interior {n:g}"] = {name: float(np.median(e[:, k])) for name, e in cell.delta_e.items()}
    out = _study_outcome(studies)
    out.details["grid_cells_median_delta_e00_over_angle"] = cells
    return out
