"""Render a ``Scene``: build it, run the C++ path tracer on all cores with a progress bar,
and return the image with its per-pixel variance and timing."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsdflab import _core
from bsdflab.util import limits
from bsdflab.util import args as check
from bsdflab.util.progress import run_with_progress
from bsdflab.render.build import build_render_scene
from bsdflab.render.scene import Scene

MAX_SPP = limits.DEFAULTS["BSDFLAB_MAX_SPP"]  # the default; BSDFLAB_MAX_SPP overrides
# Direct-light estimators: both with MIS (the default), or one alone (for validation).
STRATEGIES = {"mis": 0, "bsdf": 1, "light": 2}


@dataclass(frozen=True)
class RenderResult:
    """A rendered image.

    mean : (H, W, 3) linear sRGB radiance, the box-filtered pixel means.
    variance : (H, W, 3) the variance of each pixel mean (sample variance / spp). It needs
        at least 2 samples per pixel: with spp = 1 it is undefined, which the result says
        with ``variance_defined = False`` and a variance of zeros (never inf or NaN) --
        check the flag before using the variance (a z-test must not divide by it).
    """

    mean: np.ndarray
    variance: np.ndarray
    spp: int
    seconds: float
    invalid_samples: int
    settings: dict[str, Any] = field(default_factory=dict)
    variance_defined: bool = True
    rays_traced: int = 0
    # First-hit auxiliary images when render(aovs=True): "albedo" and "normal" (H, W, 3),
    # "mesh_id" (H, W) (-1: nothing hit); they never change mean or variance.
    aovs: dict[str, np.ndarray] | None = None

    @property
    def samples_per_second(self) -> float:
        h, w, _ = self.mean.shape
        return h * w * self.spp / self.seconds if self.seconds > 0 else float("inf")

    def summary(self) -> dict[str, Any]:
        h, w, _ = self.mean.shape
        return {**self.settings, "width": w, "height": h, "spp": self.spp,
                "render_seconds": round(self.seconds, 3),
                "samples_per_second": round(self.samples_per_second),
                "invalid_samples": self.invalid_samples, "variance_defined": self.variance_defined,
                "threads": _core.worker_count()}


def _spp(value, name: str = "spp") -> int:
    return check.integer(name, value, 1, limits.current().max_spp)


def render(scene: Scene, spp: int = 16, seed: int = 0, progress: bool = True, pass_spp: int | None = None,
           base_dir: str | None = None, cache_dir=None, strategy: str = "mis", aovs: bool = False,
           spectral: bool = False, client=None) -> RenderResult:
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
    ``client``: a ``dask.distributed.Client`` to render on its workers instead of this
    process's threads (bsdflab.distributed): the same image, bit for bit.
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a bsdflab.render.Scene, got {type(scene).__name__}")
    spp = _spp(spp)
    seed = check.seed(seed)
    if not isinstance(strategy, str) or strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {check.brief(strategy)}; known: {', '.join(STRATEGIES)}")
    if not isinstance(spectral, (bool, np.bool_)):
        raise ValueError(f"spectral must be True or False, got {check.brief(spectral)}")
    pass_spp = _spp(pass_spp, "pass_spp") if pass_spp is not None else max(1, spp // 16)
    c = scene.camera
    limits.check_count("width x height", c.width * c.height, "BSDFLAB_MAX_PIXELS")
    limits.check_bytes(f"a {c.width} x {c.height} render", limits.render_bytes(c.width, c.height))
    if client is not None:
        if base_dir is not None:
            raise ValueError("base_dir is for scene files read here; give workers absolute paths")
        if aovs:
            raise ValueError("aovs are computed by the in-process renderer only (render without client)")
        from bsdflab.distributed.render import render_on_cluster

        return render_on_cluster(client, scene, spp, int(seed), pass_spp, STRATEGIES[strategy],
                                 spectral=bool(spectral), progress=progress, cache_dir=cache_dir)
    core_scene = build_render_scene(scene, base_dir=base_dir, progress=progress, cache_dir=cache_dir,
                                    spectral=bool(spectral))
    job = _core.RenderJob(core_scene, spp, pass_spp, scene.max_depth, scene.rr_depth, int(seed), 16,
                          STRATEGIES[strategy], bool(spectral))
    start = time.perf_counter()
    run_with_progress(job, progress, unit="tile", desc="rendering")
    seconds = time.perf_counter() - start
    mean, variance = job.image()
    defined = job.spp_done >= 2
    if not defined:  # one sample per pixel: no spread to estimate
        variance = np.zeros_like(mean)
    aux = None
    if aovs:
        albedo, normal, mesh_id = job.aovs(16)
        aux = {"albedo": albedo, "normal": normal, "mesh_id": mesh_id}
    return RenderResult(mean=mean, variance=variance, spp=job.spp_done, seconds=seconds,
                        invalid_samples=job.invalid_samples, variance_defined=defined,
                        rays_traced=job.rays_traced, aovs=aux,
                        settings={"scene": scene.name, "seed": int(seed), "max_depth": scene.max_depth,
                                  "rr_depth": scene.rr_depth, "mode": "spectral" if spectral else "rgb"})
