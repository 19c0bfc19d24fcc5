"""``RenderResult``: a rendered image, its per-pixel variance and how it was made; built in
one place (``render_result``) for the in-process renderer and the work units alike."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsdflab import _core


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


def render_result(scene, mean: np.ndarray, variance: np.ndarray, spp: int, seconds: float,
                  invalid_samples: int, seed: int, spectral: bool, **extra: Any) -> RenderResult:
    """The RenderResult of a render of ``scene`` (a ``Scene``): the variance is undefined
    (zeros, ``variance_defined`` False) below 2 samples per pixel, and ``settings`` records
    the scene, seed, depths and mode. ``extra``: ``rays_traced``, ``aovs``, and ``settings``
    entries of the work-unit path (``units``, ``workers``)."""
    defined = spp >= 2
    if not defined:  # one sample per pixel: no spread to estimate
        variance = np.zeros_like(mean)
    fields_ = {k: extra.pop(k) for k in ("rays_traced", "aovs") if k in extra}
    settings = {"scene": scene.name, "seed": int(seed), "max_depth": scene.max_depth,
                "rr_depth": scene.rr_depth, "mode": "spectral" if spectral else "rgb", **extra}
    return RenderResult(mean=mean, variance=variance, spp=spp, seconds=seconds,
                        invalid_samples=int(invalid_samples), variance_defined=defined,
                        settings=settings, **fields_)
