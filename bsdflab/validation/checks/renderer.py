"""The path tracer: closed forms (a rectangle light's form factor, the white furnace) and an
image cross-check against Mitsuba 3 (side by side, difference, FLIP, per-pixel z)."""
from __future__ import annotations

import math

import numpy as np

from bsdflab.validation.checks._common import SIGNIFICANCE, z_limit
from bsdflab.validation.figures import new_figure
from bsdflab.validation.registry import REGISTRY, Outcome, effort


def _scene_modules():
    from bsdflab.render import Camera, Environment, Material, Scene, Shape, render

    return Camera, Environment, Material, Scene, Shape, render


def rectangle_form_factor(a: float, b: float, h: float) -> float:
    """Point to a parallel a x b rectangle at height h, corner above the point (Howell B-3)."""
    x, y = a / h, b / h
    return (x / math.sqrt(1 + x * x) * math.atan(y / math.sqrt(1 + x * x))
            + y / math.sqrt(1 + y * y) * math.atan(x / math.sqrt(1 + y * y))) / (2 * math.pi)


def _light_over_plane(reflectance=0.5, emission=(2.0, 1.0, 0.5)):
    Camera, _, Material, Scene, Shape, _ = _scene_modules()
    floor = Shape({"type": "rectangle", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]},
                  material="floor", name="floor")
    light = Shape({"type": "rectangle", "center": [0, 1, 0], "normal": [0, -1, 0], "size": [1.0, 2.0]},
                  emission=emission, name="light")
    camera = Camera(origin=(0.0, 0.5, 3.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov_deg=0.05,
                    width=16, height=16)
    return Scene(camera, (floor, light), {"floor": Material({"type": "diffuse", "reflectance": reflectance})},
                 max_depth=2, name="light-over-plane")


def _image_mean(result):
    n = result.mean.shape[0] * result.mean.shape[1]
    return result.mean.reshape(n, -1).mean(axis=0), np.sqrt(result.variance.reshape(n, -1).sum(axis=0)) / n


@REGISTRY.check(name="renderer/closed-form/form-factor", family="renderer",
                title="Direct light from a rectangle: MIS, BSDF and light sampling vs the form factor",
                model="bsdflab.render (path tracer), strategies mis / bsdf / light",
                reference="closed form L = rho L_e F, F from Howell's catalogue (configuration B-3)",
                statistic="max |z| of the image mean over strategies x channels",
                tolerance=f"two-sided normal quantile Sidak-corrected at {SIGNIFICANCE} over 9 z's; "
                          "the renderer's per-pixel variance gives the standard error of the mean",
                effort=effort({"spp": 32}, {"spp": 256}), seed=51)
def _form_factor(ctx):
    render = _scene_modules()[-1]
    expected = 0.5 * np.array([2.0, 1.0, 0.5]) * 4 * rectangle_form_factor(0.5, 1.0, 1.0)
    zs = {}
    for strategy in ("mis", "bsdf", "light"):
        r = render(_light_over_plane(), spp=int(ctx.effort["spp"]), seed=ctx.seed, progress=False, strategy=strategy)
        mean, err = _image_mean(r)
        zs[strategy] = (mean - expected) / err
    worst = float(max(np.max(np.abs(z)) for z in zs.values()))
    limit = z_limit(9)
    return Outcome(worst < limit, worst, limit, "<", "z per strategy: " + ", ".join(
        f"{k} {np.round(v, 2).tolist()}" for k, v in zs.items()), {"expected": expected, "z": zs})


@REGISTRY.check(name="renderer/closed-form/white-furnace", family="renderer",
                title="A white diffuse sphere in a uniform environment is invisible",
                model="bsdflab.render, Diffuse(1.0) sphere, 64 bounces", reference="closed form: every pixel = 1",
                statistic="max |z| per pixel-channel of (pixel - 1)",
                tolerance=f"two-sided normal quantile Sidak-corrected at {SIGNIFICANCE} over all pixel-channels",
                effort=effort({"spp": 32}, {"spp": 128}), seed=52)
def _white_furnace(ctx):
    Camera, Environment, Material, Scene, Shape, render = _scene_modules()
    scene = Scene(Camera(origin=(0.0, 0.0, 4.0), target=(0.0, 0.0, 0.0), fov_deg=40.0, width=24, height=24),
                  (Shape({"type": "sphere", "center": [0, 0, 0], "radius": 1.0, "subdivisions": 64},
                         material="white", name="object"),),
                  {"white": Material({"type": "diffuse", "reflectance": 1.0})},
                  environment=Environment("constant", radiance=(1.0, 1.0, 1.0)), max_depth=64, rr_depth=64)
    r = render(scene, spp=int(ctx.effort["spp"]), seed=ctx.seed, progress=False)
    sd = np.sqrt(r.variance)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(sd > 0, (r.mean - 1.0) / sd, np.where(np.abs(r.mean - 1) < 1e-9, 0.0, np.inf))
    limit = z_limit(z.size)
    fig, (a, b) = new_figure(8.0, 3.2, cols=2)
    a.imshow(np.clip(r.mean, 0, 2) / 2)
    a.set_title("render (1 = invisible)", fontsize=8)
    im = b.imshow(z.max(axis=2), cmap="coolwarm", vmin=-limit, vmax=limit)
    fig.colorbar(im, ax=b)
    b.set_title("z of (pixel - 1)", fontsize=8)
    ctx.figure(fig, "white furnace render and its per-pixel z")
    worst = float(np.max(np.abs(z)))
    return Outcome(worst < limit, worst, limit, "<", f"max |z| {worst:.2f} over {z.size} pixel-channels")


def sphere_on_floor(width, height, environment=None):
    """A red diffuse ball on a grey floor under a square lamp and an environment (default
    a sky at scale 1.5): the scene of the image cross-checks (also tests/test_mitsuba_render.py)."""
    Camera, Environment, Material, Scene, Shape, _ = _scene_modules()
    diffuse = {"type": "diffuse", "reflectance": {"type": "rgb", "rgb": [0.8, 0.3, 0.1]}}
    grey = {"type": "diffuse", "reflectance": {"type": "constant", "value": 0.6}}
    return Scene(Camera(origin=(0.0, 1.6, 4.5), target=(0.0, 0.9, 0.0), fov_deg=45, width=width, height=height),
                 (Shape({"type": "sphere", "center": [0, 1, 0], "subdivisions": 32}, "red", name="ball"),
                  Shape({"type": "rectangle", "size": [6, 6]}, "grey", name="floor"),
                  Shape({"type": "rectangle", "center": [0, 3, 0], "normal": [0, -1, 0], "size": [2, 2]},
                        None, (4.0, 4.0, 4.0), name="lamp")),
                 {"red": Material(diffuse), "grey": Material(grey)},
                 Environment("sky", scale=1.5) if environment is None else environment,
                 max_depth=5, rr_depth=3)


def _to_ldr(img, white):
    return np.clip(np.clip(img, 0, None) / white, 0, 1) ** (1 / 2.2)


def image_figure(ctx, ours, theirs, test, labels=("bsdflab", "Mitsuba 3")):
    """Side by side, difference, FLIP and z-map of an image z-test (figure + FLIP mean)."""
    import flip_evaluator

    white = float(np.percentile(np.concatenate([ours.ravel(), theirs.ravel()]), 99)) or 1.0
    a, b = _to_ldr(ours, white), _to_ldr(theirs, white)
    flip_map, flip_mean, _ = flip_evaluator.evaluate(b.astype(np.float32), a.astype(np.float32), "LDR")
    fig, axes = new_figure(16.0, 3.4, cols=5)
    axes[0].imshow(a, interpolation="nearest")
    axes[0].set_title(labels[0], fontsize=8)
    axes[1].imshow(b, interpolation="nearest")
    axes[1].set_title(labels[1], fontsize=8)
    diff = (ours - theirs).mean(axis=2)
    lim = float(np.abs(diff).max()) or 1.0
    im = axes[2].imshow(diff, cmap="coolwarm", vmin=-lim, vmax=lim, interpolation="nearest")
    fig.colorbar(im, ax=axes[2], fraction=0.046)
    axes[2].set_title("difference (mean over RGB)", fontsize=8)
    im = axes[3].imshow(np.asarray(flip_map).squeeze(), cmap="magma", vmin=0, vmax=1, interpolation="nearest")
    fig.colorbar(im, ax=axes[3], fraction=0.046)
    axes[3].set_title(f"FLIP (mean {flip_mean:.3f})", fontsize=8)
    z = np.nan_to_num(test.z, nan=0.0, posinf=99, neginf=-99)
    strongest = np.take_along_axis(z, np.argmax(np.abs(z), axis=2)[..., None], axis=2)[..., 0]
    crit = z_limit(max(test.n_tested, 1), test.alpha)
    im = axes[4].imshow(np.clip(strongest, -crit, crit), cmap="coolwarm", vmin=-crit, vmax=crit,
                        interpolation="nearest")
    fig.colorbar(im, ax=axes[4], fraction=0.046)
    axes[4].set_title(f"z (|z| > {crit:.2f} rejected)", fontsize=8)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    ctx.figure(fig, f"{labels[0]} | {labels[1]} | difference | FLIP | per-pixel z: {test.summary()}")
    return float(flip_mean)


MITSUBA_IMAGE_TOLERANCE = ("0 rejections at family-wise alpha 1e-3 (Sidak over all pixel-channels; "
                           "both images' per-pixel variances of the mean, plus 1e-4 relative for float32)")
MITSUBA_IMAGE_EFFORT = effort({"width": 32, "height": 24, "spp": 256}, {"width": 48, "height": 36, "spp": 1024},
                              {"width": 96, "height": 72, "spp": 4096})


@REGISTRY.check(name="renderer/mitsuba/sphere-on-floor", family="renderer",
                title="Sphere on a floor under an area light and a sky: bsdflab against Mitsuba 3",
                model="bsdflab.render (path tracer, MIS)", reference="Mitsuba 3 path integrator (moments for variance)",
                statistic="rejected pixel-channels of the per-pixel two-sample z-test",
                tolerance=MITSUBA_IMAGE_TOLERANCE, effort=MITSUBA_IMAGE_EFFORT,
                seed=53, requires=("mitsuba", "flip_evaluator"))
def _sphere_vs_mitsuba(ctx):
    e = ctx.effort
    return _versus_mitsuba(ctx, sphere_on_floor(int(e["width"]), int(e["height"])), spectral=False)


@REGISTRY.check(name="renderer/mitsuba/sphere-on-floor-spectral", family="renderer",
                title="Spectral mode: the sphere on a floor under a coloured constant sky against Mitsuba 3's "
                      "spectral variant",
                model="bsdflab.render(spectral=True) (81 bins, MIS)",
                reference="Mitsuba 3 llvm_ad_spectral (scalar_spectral without LLVM 19) path integrator, given "
                          "our spectra as 5 nm step functions and scored by our sensor W "
                          "(reference/mitsuba_spectral.py; residual <= 1e-4 relative)",
                statistic="rejected pixel-channels of the per-pixel two-sample z-test",
                tolerance=MITSUBA_IMAGE_TOLERANCE, effort=MITSUBA_IMAGE_EFFORT,
                seed=54, requires=("mitsuba", "flip_evaluator"))
def _sphere_vs_mitsuba_spectral(ctx):
    Environment = _scene_modules()[1]
    e = ctx.effort
    sky = Environment("constant", radiance=(0.6, 0.7, 0.9))  # Mitsuba takes no per-texel spectra
    return _versus_mitsuba(ctx, sphere_on_floor(int(e["width"]), int(e["height"]), sky), spectral=True)


def _versus_mitsuba(ctx, scene, spectral: bool):
    from bsdflab.reference.mitsuba_render import render_mitsuba
    from bsdflab.testing import image_z_test

    render = _scene_modules()[-1]
    spp = int(ctx.effort["spp"])
    ours = render(scene, spp=spp, seed=ctx.seed, progress=False, spectral=spectral)
    theirs = render_mitsuba(scene, spp, seed=ctx.seed + 1, spectral=spectral)
    test = image_z_test(ours.mean, ours.variance, *theirs, alpha=1e-3)
    labels = ("bsdflab spectral", "Mitsuba 3 spectral") if spectral else ("bsdflab", "Mitsuba 3")
    flip_mean = image_figure(ctx, ours.mean, theirs[0], test, labels)
    return Outcome(test.passed, test.n_rejected, 0, "<=", test.summary(),
                   {"flip_mean": flip_mean, "min_p": test.min_p, "worst_z": test.worst_z,
                    "pixel_channels": test.n_tested})


# Point, spot and directional lights with the lamp (an area light) and the sky: several
# emitters, so both renderers' light selection and delta-light weights are exercised.
MIXED_LIGHTS = ({"type": "point", "position": [1.2, 2.2, 1.0], "intensity": [6.0, 5.0, 4.0]},
                {"type": "spot", "position": [-1.0, 2.5, 1.5], "direction": [1.0, -1.5, -1.5], "intensity": 14.0,
                 "cutoff_angle_deg": 25.0, "beam_width_deg": 15.0},
                {"type": "directional", "direction": [0.4, -1.0, -0.3], "irradiance": [1.2, 1.1, 1.0]})


@REGISTRY.check(name="renderer/mitsuba/lights-mixed", family="renderer",
                title="Point, spot and directional lights with an area light and a sky: bsdflab against Mitsuba 3",
                model="bsdflab.render (delta lights by next-event estimation, uniform emitter selection, MIS)",
                reference="Mitsuba 3 path integrator with its point, spot and directional emitters",
                statistic="rejected pixel-channels of the per-pixel two-sample z-test",
                tolerance=MITSUBA_IMAGE_TOLERANCE, effort=MITSUBA_IMAGE_EFFORT,
                seed=55, requires=("mitsuba", "flip_evaluator"))
def _lights_vs_mitsuba(ctx):
    from dataclasses import replace

    e = ctx.effort
    scene = replace(sphere_on_floor(int(e["width"]), int(e["height"])), lights=MIXED_LIGHTS)
    return _versus_mitsuba(ctx, scene, spectral=False)
