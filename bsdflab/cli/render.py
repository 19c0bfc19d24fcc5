"""`bsdflab render`: render a named scene or a scene file to EXR (linear) and PNG (sRGB)."""
from __future__ import annotations

import argparse
import json
import os

from bsdflab.cli.cluster_options import add_cluster_options, client_from_args


def register(sub) -> None:
    p = sub.add_parser("render", help="path-trace a scene (snake, sphere, torus, ...) to EXR + PNG",
                       description="Render a built-in scene (tabulating its materials on first use, "
                                   "then reusing the cached tables) or a scene file (.json). Writes a "
                                   "linear EXR and a tone-mapped sRGB PNG beside it; scenes that are "
                                   "a set (appearance-grid, ablation) become a labelled contact sheet.")
    p.add_argument("scene", nargs="?", help="scene name (see --list) or a scene file path ending in .json")
    p.add_argument("--list", action="store_true", help="list the built-in scenes and exit")
    p.add_argument("--width", type=int, default=None, help="image width in pixels (default: the scene's)")
    p.add_argument("--height", type=int, default=None, help="image height in pixels (default: the scene's)")
    p.add_argument("--spp", type=int, default=64, help="samples per pixel (default 64)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--max-depth", type=int, default=None, help="longest path in vertices (default: the scene's)")
    p.add_argument("--option", "-o", action="append", default=[], metavar="KEY=VALUE",
                   help="scene option, e.g. -o material=direct or -o variant=full (repeatable); "
                        "-o light=<light JSON or type> adds a light, e.g. -o light=sun or "
                        "-o 'light={\"type\": \"point\", \"position\": [0, 50, 0], \"intensity\": 2000}' "
                        "(docs/scene_format.md, Lights)")
    p.add_argument("--out", default="render.exr", help="output EXR path (default render.exr); "
                                                       "the PNG goes beside it")
    p.add_argument("--exposure", type=float, default=0.0, help="PNG exposure in stops (default 0)")
    p.add_argument("--save-scene", default=None, help="also write the scene as a scene file (.json)")
    p.add_argument("--cache-dir", default=None, help="table cache folder (default: the user cache)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    add_cluster_options(p)
    p.add_argument("--spectral", action="store_true",
                   help="spectral transport over 81 wavelength bins instead of RGB (slower; spectra multiply "
                        "at every bounce, see docs/spectral_rendering.md)")
    p.add_argument("--denoise", action="store_true",
                   help="also write a denoised preview (Intel Open Image Denoise via pyoidn) beside the EXR "
                        "as <out>.denoised.exr / .png; the EXR itself is unchanged")
    p.set_defaults(run=run)


def _options(pairs: list[str]) -> dict:
    from bsdflab.cli.key_values import key_values

    return key_values(pairs, "--option")


def _scenes(args):
    """[(label, Scene)] and the folder relative paths resolve against."""
    from bsdflab.scenes import SCENE_SETS, SCENES, scene, scene_set
    from bsdflab.scenes.scene_file import load_scene

    kwargs = _options(args.option)
    extra = _extra_lights(kwargs)
    if args.scene.endswith(".json"):
        if kwargs:
            raise ValueError("--option applies to built-in scenes, not scene files (except light= and lights=)")
        return _lit([("", load_scene(args.scene))], extra), os.path.dirname(os.path.abspath(args.scene))
    if args.scene in SCENE_SETS:
        return _lit(scene_set(args.scene, **kwargs), extra), None
    if args.scene not in SCENES:
        raise ValueError(f"unknown scene {args.scene!r}; known scenes: {', '.join([*SCENES, *SCENE_SETS])} "
                         "(or a .json file)")
    return _lit([("", scene(args.scene, **kwargs))], extra), None


def _extra_lights(kwargs: dict) -> list:
    """The lights ``-o light=...`` (one: a light dict, or a bare type name such as ``sun``
    for its defaults) and ``-o lights=[...]`` add to the scene; taken out of ``kwargs``."""
    from bsdflab.render.lights import lights_of

    extra = []
    if "light" in kwargs:
        one = kwargs.pop("light")
        extra.append({"type": one} if isinstance(one, str) else one)
    if "lights" in kwargs:
        many = kwargs.pop("lights")
        if not isinstance(many, list):
            raise ValueError(f"--option lights= must be a JSON list of light dicts, got {many!r}")
        extra += many
    try:
        return list(lights_of(extra))
    except ValueError as e:
        raise ValueError(f"--option light: {e}") from None


def _lit(scenes: list, extra: list) -> list:
    from dataclasses import replace

    if not extra:
        return scenes
    return [(label, replace(s, lights=(*s.lights, *extra))) for label, s in scenes]


def _list_scenes() -> int:
    from bsdflab.scenes import SCENE_SETS, SCENES

    for name, make in {**SCENES, **SCENE_SETS}.items():
        first = ((make.__doc__ or "").strip().splitlines() or [""])[0]
        print(f"{name:<18} {first}")
    return 0


def _check_arguments(args: argparse.Namespace) -> str:
    """Every argument checked and every output folder writable before anything renders;
    returns the PNG path."""
    from bsdflab.cli.errors import check_writable
    from bsdflab.scenes import SCENE_SETS

    if args.scene is None:
        raise ValueError("name a scene or a scene file (.json); bsdflab render --list lists the scenes")
    if not (abs(args.exposure) <= 64):  # also rejects NaN
        raise ValueError(f"--exposure must be a number of stops in [-64, 64], got {args.exposure}")
    if not args.out.lower().endswith(".exr"):
        raise ValueError(f"--out must end in .exr, got {args.out!r}")
    png = os.path.splitext(args.out)[0] + ".png"
    check_writable(args.out, "--out")  # before the render, not after it
    check_writable(png, "--out (its PNG)")
    if args.save_scene:
        check_writable(args.save_scene, "--save-scene")
    if args.denoise and args.scene in SCENE_SETS:
        raise ValueError("--denoise works on a single scene, not a scene set")
    return png


def _prepared(args: argparse.Namespace, scenes) -> list:
    """The scenes with the command line's size and depth applied (to every scene of a set)."""
    from dataclasses import replace

    prepared = []
    for label, s in scenes:
        if args.width is not None or args.height is not None:
            s = s.with_resolution(s.camera.width if args.width is None else args.width,
                                  s.camera.height if args.height is None else args.height)
        if args.max_depth is not None:
            s = replace(s, max_depth=args.max_depth)
        prepared.append((label, s))
    return prepared


def _write_one(args: argparse.Namespace, png: str, result) -> dict:
    """The EXR and the PNG appear together or not at all; a denoised preview goes beside
    the unbiased EXR, never instead of it."""
    from bsdflab.render.image_io import write_exr_and_png

    summary = result.summary()
    write_exr_and_png(args.out, png, result.mean, summary, args.exposure)
    if args.denoise:
        from bsdflab.render.denoise import denoise

        stem = os.path.splitext(args.out)[0] + ".denoised"
        write_exr_and_png(stem + ".exr", stem + ".png", denoise(result),
                          dict(summary, denoised="Intel Open Image Denoise (pyoidn)"), args.exposure)
        print(f"wrote the denoised preview {stem}.exr and {stem}.png")
    return summary


def _write_set(args: argparse.Namespace, png: str, results) -> dict:
    """A scene set: the EXR mosaic and the labelled contact sheet, published together."""
    from bsdflab.plots.contact_sheet import contact_sheet, mosaic
    from bsdflab.render.image_io import EXR_SUFFIX, PNG_SUFFIX, exr_writer
    from bsdflab.util.files import write_together

    items = [(label, r.mean) for label, r in results]
    sheet = mosaic([im for _, im in items], min(len(items), 3))
    write_together([(args.out, exr_writer(sheet, {"scene": args.scene}), EXR_SUFFIX),
                    (png, lambda tmp: contact_sheet(items, tmp, args.exposure, title=args.scene), PNG_SUFFIX)])
    return {"scene": args.scene, "images": [dict(r.summary(), label=label) for label, r in results]}


def run(args: argparse.Namespace) -> int:
    from bsdflab.render import render
    from bsdflab.scenes.scene_file import save_scene

    if args.list:
        return _list_scenes()
    png = _check_arguments(args)
    scenes, base_dir = _scenes(args)
    prepared = _prepared(args, scenes)
    if args.save_scene:
        if len(prepared) != 1:
            raise ValueError("--save-scene needs a single scene, not a set")
        save_scene(prepared[0][1], args.save_scene)
    results = []
    with client_from_args(args) as client:
        for label, s in prepared:
            if label and not args.quiet:
                print(f"rendering {label}")
            results.append((label, render(s, spp=args.spp, seed=args.seed, progress=not args.quiet,
                                          base_dir=base_dir, cache_dir=args.cache_dir, aovs=args.denoise,
                                          spectral=args.spectral, client=client)))
    summary = _write_one(args, png, results[0][1]) if len(results) == 1 else _write_set(args, png, results)
    print(json.dumps(summary, indent=1))
    print(f"wrote {args.out} and {png}")
    return 0
