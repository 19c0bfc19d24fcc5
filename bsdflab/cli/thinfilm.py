"""`bsdflab thinfilm`: plot a thin film's (or the iridophore stack's) reflected colour."""
from __future__ import annotations

import argparse

from bsdflab.presets import AIR_IOR, CYTOPLASM_IOR, FILM_THICKNESS_NM, GUANINE_IOR, KERATIN_IOR_550, iridophore_stack
from bsdflab.util.args import real_scalar

DEFAULT_THICKNESS_RANGE_NM = (0.0, 1200.0)


def register(sub) -> None:
    p = sub.add_parser(
        "thinfilm", help="plot a thin film's reflectance and colour (PNG)",
        description="Plot a thin film's reflectance spectra, its reflected sRGB colour over "
                    "angle x thickness, and that colour next to a three-wavelength "
                    "'RGB' (650/510/475 nm), which aliases. Defaults: the snake's guanine "
                    "film on keratin.")
    g = p.add_argument_group("film")
    g.add_argument("--film-ior", type=float, default=None,
                   help=f"film index (default guanine, {GUANINE_IOR})")
    g.add_argument("--thickness", type=float, default=None, metavar="NM",
                   help=f"film thickness in nm (default {FILM_THICKNESS_NM:g})")
    g.add_argument("--ext-ior", type=float, default=AIR_IOR,
                   help=f"index of the medium light comes from (default air, {AIR_IOR})")
    g.add_argument("--substrate-ior", type=float, default=KERATIN_IOR_550,
                   help=f"substrate index (default keratin at 550 nm, {KERATIN_IOR_550:.4f})")
    g.add_argument("--preset-stack", action="store_true",
                   help="use the 5-platelet guanine/cytoplasm iridophore stack "
                        "(bsdflab.presets.iridophore_stack) instead of one film")
    p.add_argument("--thickness-range", type=float, nargs=2, metavar=("MIN", "MAX"),
                   default=DEFAULT_THICKNESS_RANGE_NM,
                   help="thickness axis of the image in nm (a stack's total thickness, all "
                        "layers scaled together); default 0 1200")
    p.add_argument("--out", default="thinfilm.png", help="output PNG path (default thinfilm.png)")
    p.set_defaults(run=run)


def film_from_args(args: argparse.Namespace):
    """(film, title, thickness label) from the options; ValueError for bad values."""
    from bsdflab.optics import FilmLayer, FilmStack

    ext = real_scalar("--ext-ior", args.ext_ior, 0.0, lo_open=True)
    substrate = real_scalar("--substrate-ior", args.substrate_ior, 0.0, lo_open=True)
    media = f"on {_n(substrate, KERATIN_IOR_550, 'keratin')}, from {_n(ext, AIR_IOR, 'air')}"
    if args.preset_stack:
        if args.film_ior is not None or args.thickness is not None:
            raise ValueError("--film-ior and --thickness describe one film; --preset-stack "
                             "uses the iridophore stack's own layers")
        spec = iridophore_stack()
        platelet, gap = spec[0], spec[1]
        title = (f"Iridophore stack: {len(spec[::2])} platelets "
                 f"({_n(platelet['material'], GUANINE_IOR, 'guanine')}, "
                 f"{platelet['thickness_nm']:g} nm) with gaps "
                 f"({_n(gap['material'], CYTOPLASM_IOR, 'cytoplasm')}, "
                 f"{gap['thickness_nm']:g} nm), {media}")
        layers = [FilmLayer(layer["material"], layer["thickness_nm"]) for layer in spec]
        return FilmStack(ext, layers, substrate), title, "total stack thickness"
    n_film = real_scalar("--film-ior", GUANINE_IOR if args.film_ior is None else args.film_ior,
                         0.0, lo_open=True)
    d = real_scalar("--thickness",
                    FILM_THICKNESS_NM if args.thickness is None else args.thickness, 0.0)
    title = (f"Thin film: {_n(n_film, GUANINE_IOR, 'guanine')}, {d:g} nm thick, {media} "
             "(unpolarised light)")
    return (ext, n_film, d, substrate), title, "film thickness"


def _n(index: float, preset: float | None = None, name: str = "") -> str:
    """An index without float noise, named when it is that preset's ("air n 1.000277")."""
    return f"{name + ' ' if index == preset else ''}n {index:.7g}"


def thickness_range_from_args(args: argparse.Namespace) -> tuple[float, float]:
    lo = real_scalar("--thickness-range MIN", args.thickness_range[0], 0.0)
    hi = real_scalar("--thickness-range MAX", args.thickness_range[1], lo, lo_open=True)
    return lo, hi


def run(args: argparse.Namespace) -> int:
    from bsdflab.plots.thin_film import thin_film_figure

    film, title, label = film_from_args(args)
    summary = thin_film_figure(film, args.out, thickness_range_from_args(args), title, label)
    three, spectral = summary["three_wavelength"], summary["spectral"]
    print(f"film                      {title}")
    print("at normal incidence:")
    print(f"  spectral sRGB (linear)  R {spectral[0]:.4f}  G {spectral[1]:.4f}  "
          f"B {spectral[2]:.4f}   (CIE 1931, D65, {summary['step_nm']:.3g} nm grid)")
    print(f"  3-wavelength 'RGB'      R {three[0]:.4f}  G {three[1]:.4f}  B {three[2]:.4f}"
          "   (R at 650, 510, 475 nm)")
    print(f"  difference              Delta E 2000 = {summary['delta_e']:.1f}")
    print(f"wrote                     {args.out}")
    return 0
