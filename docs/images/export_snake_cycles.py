"""Figure: the snake exported to Blender, rendered by Cycles, beside bsdflab's render of the
exact material, with the Delta E00 map between them (docs/export.md).

    .venv/bin/python docs/images/export_snake_cycles.py   # a few minutes; writes export_snake_cycles.png

Both see the export's snake scene: the snake's mesh (no scale texture) under a constant white
world, the snake camera of bsdflab.scenes.snake. Cycles renders the exported .blend's "snake"
scene (the fitted Principled BSDF); bsdflab renders the xenopeltis preset itself (PFMC at
every hit, one walk). Delta E00 per 4 x 4 block of pixels (linear sRGB, D65), where both
see the snake.
"""
from __future__ import annotations

import os
import sys
import tempfile

import numpy as np

W, H, SPP_CYCLES, SPP_BSDFLAB, BLOCK = 240, 136, 64, 64, 4
HERE = os.path.dirname(os.path.abspath(__file__))

RENDER_SNAKE = '''import sys
import bpy
blend, out, w, h, spp = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.wm.open_mainfile(filepath=blend)
scene = bpy.data.scenes["snake"]
scene.render.resolution_x, scene.render.resolution_y = int(w), int(h)
scene.render.resolution_percentage = 100
scene.cycles.samples = int(spp)
scene.cycles.seed = 0
scene.cycles.use_adaptive_sampling = False
scene.cycles.pixel_filter_type = "BOX"
scene.cycles.filter_width = 1.0
scene.render.film_transparent = False
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.filepath = out
bpy.ops.render.render(write_still=True, scene="snake")
'''


def bsdflab_render():
    from bsdflab.render import Environment, Scene
    from bsdflab.render.render import render
    from bsdflab.scenes.snake import snake

    s = snake(W, H, material="direct", scales=False, eyes=False)
    shapes = [x for x in s.shapes if x.name in ("body", "head")]
    scene = Scene(s.camera, shapes, {k: s.materials[k] for k in ("skin", "head")},
                  Environment(type="constant", radiance=(1.0, 1.0, 1.0)), max_depth=8)
    return render(scene, spp=SPP_BSDFLAB, seed=0, progress=False, aovs=True)


def main() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bsdflab.export import export
    from bsdflab.export.blender import run_bpy
    from bsdflab.presets import preset
    from bsdflab.reference.approximations.study import delta_e00
    from bsdflab.render.image_io import read_exr

    with tempfile.TemporaryDirectory() as tmp:
        blend = os.path.join(tmp, "snake.blend")
        report = export(preset("xenopeltis"), "blender", blend)
        run_bpy(RENDER_SNAKE, [blend, os.path.join(tmp, "snake.exr"), str(W), str(H), str(SPP_CYCLES)])
        cyc = read_exr(os.path.join(tmp, "snake.exr"))
    ours = bsdflab_render()
    mask = ours.aovs["mesh_id"] >= 0   # where bsdflab sees the snake (blocks on its edge are left out)
    rgb_c, rgb_b = cyc[..., :3], ours.mean

    def blocks(x):
        h, w = (x.shape[0] // BLOCK) * BLOCK, (x.shape[1] // BLOCK) * BLOCK
        x = x[:h, :w]
        return x.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, *x.shape[2:]).mean(axis=(1, 3))

    keep = blocks(mask.astype(float)) > 0.999
    de = np.where(keep, delta_e00(np.maximum(blocks(rgb_c), 1e-6), np.maximum(blocks(rgb_b), 1e-6)), np.nan)
    vals = de[keep]
    print(f"Delta E00 per {BLOCK}x{BLOCK} block on the snake: median {np.median(vals):.2f}, "
          f"95th percentile {np.percentile(vals, 95):.2f}, > 2 on {100 * np.mean(vals > 2):.0f} % "
          f"({keep.sum()} blocks); base colour {report['parameters']['base_color']['value']}")
    scale = 1.0 / max(np.percentile(rgb_b[mask], 99), 1e-6)

    def show(x):
        return np.clip(np.where(mask[..., None], x * scale, 1.0), 0, 1) ** (1 / 2.2)

    fig, ax = plt.subplots(1, 3, figsize=(13, 3.2), constrained_layout=True)
    ax[0].imshow(show(rgb_c))
    ax[0].set_title(f"Cycles (bpy 5.0.1), exported .blend, {SPP_CYCLES} spp")
    ax[1].imshow(show(rgb_b))
    ax[1].set_title(f"bsdflab, exact layered model (PFMC), {SPP_BSDFLAB} spp")
    im = ax[2].imshow(de, cmap="magma", vmin=0, vmax=4)
    ax[2].set_title(f"Delta E00 ({BLOCK}x{BLOCK} blocks): median {np.median(vals):.2f}")
    fig.colorbar(im, ax=ax[2])
    for a in ax:
        a.set_axis_off()
    fig.savefig(os.path.join(HERE, "export_snake_cycles.png"), dpi=80)


if __name__ == "__main__":
    sys.exit(main())
