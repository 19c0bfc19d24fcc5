"""The thin-film figure: spectra, colour over (angle x thickness), and the aliasing of the
three-wavelength colour next to bsdflab's spectral colour.

Panels
------
(a) Unpolarised reflectance vs wavelength at 0, 30, 60 and 75 degrees, with the three
    sample wavelengths of the three-wavelength colour marked.
(b) The reflected colour over angle of incidence x thickness: each pixel is the linear
    sRGB (CIE 1931 2 degree, D65) of the reflectance spectrum, shown through
    `display_srgb` with one gain k >= 1 for the whole figure (the 99th percentile of
    max(R, G, B) at <= 60 degrees maps to 1; brighter pixels are scaled down keeping
    their hue). A flat reflectance of 1/k shows as white.
(c) The colour vs angle at the film's thickness, spectral above three-wavelength.
(d) The colour vs thickness at normal incidence, spectral above three-wavelength: where
    fringes crowd the visible range, the spectral colour fades towards grey while
    the three samples keep cycling through saturated colours.
"""
from __future__ import annotations

import numpy as np

from bsdflab.plots.film_colour import (
    colour_wavelengths,
    delta_e_2000,
    display_exposure,
    display_srgb,
    film_thickness_nm,
    optical_thickness_nm,
    reflectance,
    spectral_rgb,
    three_wavelength_colour,
)
from bsdflab.plots.lobe import save_figure
from bsdflab.spectra import THREE_WAVELENGTHS_NM

SPECTRUM_ANGLES_DEG = (0.0, 30.0, 60.0, 75.0)
IMAGE_ANGLES_DEG = np.linspace(0.0, 89.0, 90)  # 1 deg; bilinear display fills in
IMAGE_THICKNESSES = 201
STRIP_SAMPLES = 400
_CHANNEL_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")


def thin_film_figure(film, path: str, thickness_range_nm=(0.0, 1200.0), title: str = "",
                     thickness_label: str = "film thickness") -> dict:
    """Write the figure to `path` (PNG, atomically) and return a summary.

    Parameters
    ----------
    film : FilmStack or tuple (n0, n1, d_nm, n2)
        The film (constant indices for a stack; see `bsdflab.plots.film_colour`).
    path : str
        Output PNG path; its folder is created.
    thickness_range_nm : (float, float)
        The thickness axis of panels (b) and (d) in nm; a stack's total thickness.
    title : str
        Figure title (the film in words).
    thickness_label : str
        What the thickness axis is ("film thickness", "total stack thickness").

    Returns
    -------
    dict
        "three_wavelength": R at 650, 510, 475 nm at normal incidence; "spectral": linear
        sRGB at normal incidence; "delta_e": CIEDE2000 between the two; "exposure": the
        display gain k; "step_nm": the wavelength step of the colour integration.
    """
    d_own = film_thickness_nm(film)
    thickness = np.linspace(*thickness_range_nm, IMAGE_THICKNESSES)
    # checks the thickness range before matplotlib loads: bad input fails fast
    wavelengths = colour_wavelengths(max(optical_thickness_nm(film, thickness),
                                         optical_thickness_nm(film)))
    theta = np.radians(IMAGE_ANGLES_DEG)
    image = spectral_rgb(film, theta[None, :], thickness[:, None], wavelengths)
    exposure = display_exposure(image, theta[None, :])

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12.5, 8.6), constrained_layout=True)
    grid = fig.add_gridspec(2, 2, height_ratios=(3.0, 1.25))
    _spectra_panel(fig.add_subplot(grid[0, 0]), film)
    _image_panel(fig, fig.add_subplot(grid[0, 1]), image, exposure, thickness_range_nm,
                 d_own, thickness_label)
    strip_theta = np.radians(np.linspace(0.0, 89.0, STRIP_SAMPLES))
    _strips_panel(fig.add_subplot(grid[1, 0]), film, strip_theta, None, wavelengths, exposure,
                  (0.0, 89.0), "angle of incidence [deg]",
                  f"(c) colour vs angle at {thickness_label} {d_own:g} nm")
    strip_d = np.linspace(*thickness_range_nm, STRIP_SAMPLES)
    _strips_panel(fig.add_subplot(grid[1, 1]), film, 0.0, strip_d, wavelengths, exposure,
                  thickness_range_nm, f"{thickness_label} [nm]",
                  "(d) colour vs thickness at normal incidence", mark=d_own)
    fig.suptitle(title, fontsize=12)

    spectral = spectral_rgb(film, 0.0, None, wavelengths)
    three = three_wavelength_colour(film, 0.0)
    save_figure(fig, path)
    plt.close(fig)
    return {"three_wavelength": three, "spectral": spectral,
            "delta_e": float(delta_e_2000(spectral, three)), "exposure": exposure,
            "step_nm": float(wavelengths[1] - wavelengths[0])}


def _spectra_panel(ax, film) -> None:
    """(a) R(lambda) at a few angles, on a 1 nm grid so every fringe is drawn."""
    wl = np.arange(380.0, 780.5, 1.0)
    r = reflectance(film, wl[None, :], np.radians(SPECTRUM_ANGLES_DEG)[:, None])
    shades = _angle_shades(len(SPECTRUM_ANGLES_DEG))
    for angle, curve, shade in zip(SPECTRUM_ANGLES_DEG, r, shades):
        ax.plot(wl, curve, color=shade, lw=1.6, label=f"{angle:g}°")
    for lam, colour in zip(THREE_WAVELENGTHS_NM, _CHANNEL_COLOURS):
        ax.axvline(lam, color=colour, lw=1.0, ls=":", zorder=0)
        ax.text(lam, 1.0, f"{lam:g}", color=colour, fontsize=8, ha="center", va="bottom",
                transform=ax.get_xaxis_transform())
    ax.set_xlim(wl[0], wl[-1])
    ax.set_ylim(0, 1.2 * float(r.max()))  # headroom for the legend
    ax.set_xlabel("wavelength [nm]")
    ax.set_ylabel("reflectance R (unpolarised)")
    ax.set_title("(a) reflectance spectrum; dotted: the 3 RGB wavelengths", fontsize=10,
                 pad=16)
    ax.grid(alpha=0.3)
    ax.legend(title="angle of incidence", fontsize=8, title_fontsize=8, loc="upper center",
              ncol=len(SPECTRUM_ANGLES_DEG))


def _angle_shades(count: int):
    """Dark-to-light shades, so that larger angles read as lighter curves."""
    import matplotlib.pyplot as plt

    return [plt.get_cmap("viridis")(x) for x in np.linspace(0.0, 0.85, count)]


def _image_panel(fig, ax, image, exposure, thickness_range_nm, d_own, thickness_label) -> None:
    """(b) sRGB of the reflection over angle x thickness."""
    ax.imshow(display_srgb(image, exposure), origin="lower", aspect="auto",
              interpolation="bilinear",
              extent=(IMAGE_ANGLES_DEG[0], IMAGE_ANGLES_DEG[-1], *thickness_range_nm))
    if thickness_range_nm[0] <= d_own <= thickness_range_nm[1]:
        ax.axhline(d_own, color="white", lw=0.8, ls="--", alpha=0.8)
        ax.text(1.0, d_own, f" {d_own:g} nm", color="white", fontsize=8, va="bottom")
    ax.set_xlabel("angle of incidence [deg]")
    ax.set_ylabel(f"{thickness_label} [nm]")
    ax.set_title("(b) reflected colour (spectral sRGB, D65)\n"
                 f"pixel = sRGB of R(λ) × {exposure:.1f}: white ≙ R = {1 / exposure:.2f}; "
                 "brighter pixels scaled to fit", fontsize=10)


def _strips_panel(ax, film, theta, thickness, wavelengths, exposure, extent_x, xlabel,
                  title, mark=None) -> None:
    """Two swatch strips: spectral colour above, three-wavelength colour below."""
    spectral = spectral_rgb(film, theta, thickness, wavelengths)
    three = three_wavelength_colour(film, theta, thickness)
    strips = display_srgb(np.stack([three, spectral]), exposure)  # row 0 drawn at the bottom
    ax.imshow(strips, origin="lower", aspect="auto", interpolation="nearest",
              extent=(*extent_x, -0.5, 1.5))
    ax.set_yticks([0, 1], ["3 wavelengths\n650/510/475 nm", "spectral\n(CIE 1931, D65)"],
                  fontsize=8)
    ax.axhline(0.5, color="white", lw=1.5)
    if mark is not None and extent_x[0] <= mark <= extent_x[1]:
        ax.plot([mark], [1.5], marker="v", color="k", clip_on=False, ms=6)
    ax.set_xlabel(xlabel)
    ax.set_title(title, fontsize=10)
