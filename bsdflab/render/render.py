"""Render a ``Scene``: build it, run the C++ path tracer on all cores with a progress bar,
and return the image with its per-pixel variance and timing."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _core
from .._jobs import run_with_progress
from .build import build_render_scene
from .scene import Scene

MAX_SPP = 1 << 20
# Direct-light estimators: both with MIS (the default), or one alone (for validation).
STRATEGIES = {"mis": 0, "bsdf": 1, "light": 2}


@dataclass(frozen=True)
class RenderResult:
    """A rendered image.

    mean : (H, W, 3) linear sRGB radiance, the box-filtered pixel means.
    variance : (H, W, 3) the variance of each pixel mean (sample variance / spp).
    """

    mean: np.ndarray
    variance: np.ndarray
    spp: int
    seconds: float
    invalid_samples: int
    settings: dict[str, Any] = field(default_factory=dict)
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
                "invalid_samples": self.invalid_samples, "threads": _core.worker_count()}


def _spp(value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= MAX_SPP:
        raise ValueError(f"spp must be an integer in [1, {MAX_SPP}], got {value!r}")
    return int(value)


def render(scene: Scene, spp: int = 16, seed: int = 0, progress: bool = True, pass_spp: int | None = None,
           base_dir: str | None = None, cache_dir=None, strategy: str = "mis", aovs: bool = False,
           spectral: bool = False) -> RenderResult:
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
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a bsdflab.render.Scene, got {type(scene).__name__}")
    spp = _spp(spp)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**64:
        raise ValueError(f"seed must be an integer in [0, 2^64), got {seed!r}")
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {strategy!r}; known: {', '.join(STRATEGIES)}")
    if not isinstance(spectral, (bool, np.bool_)):
        raise ValueError(f"spectral must be True or False, got {spectral!r}")
    pass_spp = _spp(pass_spp) if pass_spp is not None else max(1, spp // 16)
    core_scene = build_render_scene(scene, base_dir=base_dir, progress=progress, cache_dir=cache_dir)
    job = _core.RenderJob(core_scene, spp, pass_spp, scene.max_depth, scene.rr_depth, int(seed), 16,
                          STRATEGIES[strategy], bool(spectral))
    start = time.perf_counter()
    run_with_progress(job, progress, unit="tile", desc="rendering")
    seconds = time.perf_counter() - start
    mean, variance = job.image()
    aux = None
    if aovs:
        albedo, normal, mesh_id = job.aovs(16)
        aux = {"albedo": albedo, "normal": normal, "mesh_id": mesh_id}
    return RenderResult(mean=mean, variance=variance, spp=job.spp_done, seconds=seconds,
                        invalid_samples=job.invalid_samples, rays_traced=job.rays_traced, aovs=aux,
                        settings={"scene": scene.name, "seed": int(seed), "max_depth": scene.max_depth,
                                  "rr_depth": scene.rr_depth, "mode": "spectral" if spectral else "rgb"})
