"""``render(scene, ..., client=...)``: the same image as the local renderer, from a cluster."""
from __future__ import annotations

import time

import numpy as np

from bsdflab.distributed.driver import run_units, token
from bsdflab.distributed.render_units import DEFAULT_UNIT_SAMPLES, job_settings, plan_units, render_unit, resolve_tables


def render_on_cluster(client, scene, spp: int, seed: int, pass_spp: int, strategy: int,
                      spectral: bool = False, progress: bool = True, cache_dir=None,
                      unit_samples: int = DEFAULT_UNIT_SAMPLES,
                      progress_callback=None, cancelled=None):
    """Render ``scene`` (validated by the caller) on ``client``'s workers; returns the
    RenderResult the local renderer would, bit for bit (see render_units)."""
    from bsdflab import _core
    from bsdflab.render.render import RenderResult

    scene_dict, tables = resolve_tables(scene, progress, cache_dir, spectral=spectral)
    settings = job_settings(scene_dict, spp, pass_spp, seed, strategy, spectral)
    width, height = scene.camera.width, scene.camera.height
    units = plan_units(width, height, spp, pass_spp, unit_samples)
    passes = units[-1].pass_index + 1
    bands = sorted({(u.y0, u.y1) for u in units})

    total = np.zeros((height, width, 3)), np.zeros((height, width, 3))
    # Units arrive in any order; each band adds its passes strictly in order (the local
    # renderer's order of floating-point additions), holding early arrivals until then.
    next_pass = {b: 0 for b in bands}
    waiting: dict[tuple[int, int], dict[int, tuple]] = {b: {} for b in bands}
    invalid = 0

    def add(unit, value):
        nonlocal invalid
        band = (unit.y0, unit.y1)
        waiting[band][unit.pass_index] = value
        while next_pass[band] in waiting[band]:
            s, q, bad = waiting[band].pop(next_pass[band])
            total[0][band[0]:band[1]] += s
            total[1][band[0]:band[1]] += q
            invalid += int(bad)
            next_pass[band] += 1

    start = time.perf_counter()
    run_units(client, render_unit, [scene_dict, tables, settings], units, add,
              name=f"bsdflab-render-{token(scene_dict, settings, sorted(tables), unit_samples)}",
              progress=progress, desc="rendering", progress_callback=progress_callback,
              cancelled=cancelled)
    seconds = time.perf_counter() - start
    if any(n != passes for n in next_pass.values()):
        raise RuntimeError("distributed render: a band is missing passes")  # a driver bug, never input
    mean, variance = _core.RenderJob.finish_image(total[0], total[1], float(spp))
    defined = spp >= 2  # as the in-process renderer says it
    if not defined:
        variance = np.zeros_like(mean)
    return RenderResult(mean=mean, variance=variance, spp=spp, seconds=seconds, invalid_samples=invalid,
                        variance_defined=defined,
                        settings={"scene": scene.name, "seed": int(seed), "max_depth": scene.max_depth,
                                  "rr_depth": scene.rr_depth, "mode": "spectral" if spectral else "rgb",
                                  "units": len(units),
                                  "workers": len(client.scheduler_info().get("workers", {}))})
