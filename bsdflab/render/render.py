"""Render a ``Scene``: build it, run the C++ path tracer on all cores with a progress bar
(or in work units on a runner, bsdflab.render.units), and return the image with its
per-pixel variance and timing."""
from __future__ import annotations

import time

from bsdflab import _core
from bsdflab.render.build import build_render_scene
from bsdflab.render.result import RenderResult, render_result
from bsdflab.render.scene import Scene
from bsdflab.render.units import render_units
from bsdflab.util import args as check
from bsdflab.util import limits, runners
from bsdflab.util.progress import run_with_progress
from bsdflab.util.runners import Runner

MAX_SPP = limits.DEFAULTS["BSDFLAB_MAX_SPP"]  # the default; BSDFLAB_MAX_SPP overrides
# Direct-light estimators: both with MIS (the default), or one alone (for validation).
STRATEGIES = {"mis": 0, "bsdf": 1, "light": 2}


def _spp(value, name: str = "spp") -> int:
    return check.integer(name, value, 1, limits.current().max_spp)


def render(scene: Scene, spp: int = 16, seed: int = 0, progress: bool = True, pass_spp: int | None = None,
           base_dir: str | None = None, cache_dir=None, strategy: str = "mis", aovs: bool = False,
           spectral: bool = False, client=None, runner: Runner | None = None) -> RenderResult:
    """Path-trace ``scene`` with ``spp`` samples per pixel.

    The image does not depend on the number of threads. ``pass_spp`` sets how many samples
    each progressive pass adds (default: about 16 passes). Ctrl-C stops the render and
    raises KeyboardInterrupt; nothing is written anywhere by this function.
    Tables a material asks for (``"tabulated"``) are built or reused before rendering.
    ``spectral=True`` transports light over the 81 bins of the default 380-780 nm grid
    instead of RGB (docs/spectral_rendering.md): spectra multiply at every bounce and become
    sRGB through the project's colour weights only when light reaches the camera. RGB
    parameters (emission, Diffuse, RGB tables) are lifted by Mallett & Yuksel's basis.
    ``aovs=True`` also returns first-hit albedo, normal and mesh-id images (for a denoiser),
    computed after the render by separate rays: the image itself is the same either way.
    ``runner`` (bsdflab.util.runners): render in units of pixel bands x passes
    (bsdflab.render.units) on this runner instead of as one job on this process's threads:
    the same image, bit for bit. ``client``: a ``dask.distributed.Client``, a convenience
    for ``runner=DaskRunner(client)`` (bsdflab.distributed).
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a bsdflab.render.Scene, got {type(scene).__name__}")
    spp = _spp(spp)
    seed = check.seed(seed)
    if not isinstance(strategy, str) or strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {check.brief(strategy)}; known: {', '.join(STRATEGIES)}")
    spectral = check.flag("spectral", spectral)
    pass_spp = _spp(pass_spp, "pass_spp") if pass_spp is not None else max(1, spp // 16)
    c = scene.camera
    limits.check_count("width x height", c.width * c.height, "BSDFLAB_MAX_PIXELS")
    limits.check_bytes(f"a {c.width} x {c.height} render", limits.render_bytes(c.width, c.height))
    runner = runners.resolve(runner, client)
    if runner is not None:
        if base_dir is not None:
            raise ValueError("base_dir is for scene files read here; give workers absolute paths")
        if aovs:
            raise ValueError("aovs are computed by the in-process renderer only (render without a runner)")
        return render_units(runner, scene, spp, int(seed), pass_spp, STRATEGIES[strategy],
                            spectral=spectral, progress=progress, cache_dir=cache_dir)
    core_scene = build_render_scene(scene, base_dir=base_dir, progress=progress, cache_dir=cache_dir,
                                    spectral=spectral)
    job = _core.RenderJob(core_scene, spp, pass_spp, scene.max_depth, scene.rr_depth, int(seed), 16,
                          STRATEGIES[strategy], spectral)
    start = time.perf_counter()
    run_with_progress(job, progress, unit="tile", desc="rendering")
    seconds = time.perf_counter() - start
    mean, variance = job.image()
    aux = None
    if aovs:
        albedo, normal, mesh_id = job.aovs(16)
        aux = {"albedo": albedo, "normal": normal, "mesh_id": mesh_id}
    return render_result(scene, mean, variance, job.spp_done, seconds, job.invalid_samples, seed, spectral,
                         rays_traced=job.rays_traced, aovs=aux)
