"""Render a bsdflab ``Scene`` with Mitsuba 3: per-pixel means and the variance of each mean.

    mean, var_of_mean = render_mitsuba(scene, spp=256, seed=0)

How the variance is estimated, and why this way: Mitsuba's ``path`` integrator runs inside
a small Python integrator (``bsdflab_moments``) that passes its radiance on and also
writes R, G, B and R^2, G^2, B^2 as AOVs. With the box filter of radius 1/2 every sample
lands in exactly one pixel with weight 1, so the developed AOVs are per-pixel sample means
of x and x^2, and var_of_mean = (mean(x^2) - mean(x)^2) / (n - 1): the unbiased sample
variance over n = spp samples, divided by n. That has spp - 1 degrees of freedom per pixel,
so a z statistic built on it is as Gaussian as the sample mean itself. Alternatives were
worse: Mitsuba's own ``moment`` integrator records second moments of *XYZ*, not of RGB
(and RGB variances do not follow from XYZ ones without the cross moments); K batch means
over seeds give only K - 1 degrees of freedom, whose heavy t tails would raise the false
alarm rate of a test that looks at thousands of pixels at the 1e-6 level.

Samples go in passes of at most ``MAX_LANES`` paths (one ``mi.render`` each, seeds drawn
from ``numpy.random.SeedSequence([seed, pass])``), and the passes' moments are combined in
float64 (Chan et al.'s pairwise update), so neither memory nor float32 film accumulation
limits spp.
"""
from __future__ import annotations

import contextlib

import numpy as np

from bsdflab.render.scene import Scene

from . import mitsuba_env
from .mitsuba_scene import path_integrator, to_mitsuba_scene
from .table_plugin import scene_uses_plugin, wavefront_mode

MOMENTS_PLUGIN = "bsdflab_moments"
MAX_LANES = 1 << 20  # paths per mi.render call

_moment_variants: set[str] = set()


@contextlib.contextmanager
def _variant(name: str | None):
    """Make ``name`` the reference variant for the duration (None: keep the usual one)."""
    if name is None or name == mitsuba_env.variant():
        yield
        return
    if name not in mitsuba_env.VARIANTS:
        raise ValueError(f"variant must be None or one of {', '.join(mitsuba_env.VARIANTS)}, got {name!r}")
    previous = mitsuba_env._chosen
    mitsuba_env._chosen = name  # the module's policy is unchanged; this call just overrides it
    try:
        mitsuba_env.mitsuba()
        yield
    finally:
        mitsuba_env._chosen = previous
        mitsuba_env.mitsuba()


def _register_moments(mi) -> None:
    if mi.variant() in _moment_variants:
        return

    class MomentsIntegrator(mi.SamplingIntegrator):
        """The nested integrator's radiance, plus AOVs x and x^2 per RGB channel."""

        def __init__(self, props):
            mi.SamplingIntegrator.__init__(self, props)
            self.nested = props["nested"]

        def sample(self, scene, sampler, ray, medium=None, active=True):
            spectrum, valid, _ = self.nested.sample(scene, sampler, ray, medium, active)
            c = mi.Color3f(spectrum)
            return spectrum, valid, [c.x, c.y, c.z, c.x * c.x, c.y * c.y, c.z * c.z]

        def aov_names(self):
            return ["m1.R", "m1.G", "m1.B", "m2.R", "m2.G", "m2.B"]

        def to_string(self):
            return f"MomentsIntegrator[nested={self.nested}]"

    mi.register_integrator(MOMENTS_PLUGIN, lambda props: MomentsIntegrator(props))
    _moment_variants.add(mi.variant())


def _check(scene, spp, seed) -> None:
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a bsdflab.render.Scene, got {type(scene).__name__}")
    if isinstance(spp, bool) or not isinstance(spp, (int, np.integer)) or not 2 <= spp <= 1 << 24:
        raise ValueError(f"spp must be an integer in [2, 2^24] (a variance needs 2 samples), got {spp!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")


def _passes(spp: int, pixels: int) -> list[int]:
    per_pass = max(2, min(spp, MAX_LANES // max(pixels, 1)))
    count = -(-spp // per_pass)
    base, extra = divmod(spp, count)
    return [base + (k < extra) for k in range(count)]


def render_mitsuba(scene: Scene, spp: int, seed: int = 0, variant: str | None = None,
                   base_dir: str | None = None, bsdflab_fallback: bool = False,
                   cache_dir=None) -> tuple[np.ndarray, np.ndarray]:
    """Render ``scene`` with Mitsuba 3's ``path`` integrator.

    Returns (mean, var_of_mean), both (H, W, 3) float64 linear sRGB: the box-filtered pixel
    means and the variance of each mean. variant: None for the reference variant
    (mitsuba_env.py), or 'llvm_ad_rgb' / 'scalar_rgb'. base_dir, bsdflab_fallback and
    cache_dir as in ``to_mitsuba_scene``. Scenes with the table plugin render in
    ``wavefront_mode`` (slower: one kernel per bounce).
    """
    _check(scene, spp, seed)
    with _variant(variant):
        mi = mitsuba_env.mitsuba()
        _register_moments(mi)
        d = to_mitsuba_scene(scene, base_dir=base_dir, bsdflab_fallback=bsdflab_fallback,
                             cache_dir=cache_dir)
        d["integrator"] = {"type": MOMENTS_PLUGIN, "nested": path_integrator(scene)}
        mi_scene = mi.load_dict(d)
        plugin = scene_uses_plugin(mi_scene) and mitsuba_env.is_vectorised()
        mode = wavefront_mode() if plugin else contextlib.nullcontext()

        h, w = scene.camera.height, scene.camera.width
        n = 0
        mean = np.zeros((h, w, 3))
        m2 = np.zeros((h, w, 3))  # sum of squared deviations from the mean
        with mode:
            for k, n_k in enumerate(_passes(int(spp), h * w)):
                pass_seed = int(np.random.SeedSequence([int(seed), k]).generate_state(1)[0])
                img = np.asarray(mi.render(mi_scene, spp=n_k, seed=pass_seed), dtype=np.float64)
                mean_k, sq_k = img[..., 3:6], img[..., 6:9]
                m2_k = n_k * np.maximum(sq_k - mean_k**2, 0.0)
                delta = mean_k - mean
                total = n + n_k
                mean += delta * (n_k / total)
                m2 += m2_k + delta**2 * (n * n_k / total)
                n = total
    return mean, m2 / (n - 1) / n
