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

Spectral mode (``spectral=True``, a Mitsuba spectral variant): the nested integrator's
radiance is at the sample's four wavelengths, and the integrator scores it with our sensor
instead of Mitsuba's CIE film: RGB = mean_j W[:, l(λ_j)] L(λ_j) / (Δλ p(λ_j)), the step
function of our colour weights W (mitsuba_spectral.py), whose expectation is exactly our
renderer's Σ_l W[:, l] v_l for the step spectra the converter hands Mitsuba. The moments
are then of that RGB, as above.

Samples go in passes of at most ``MAX_LANES`` paths (one ``mi.render`` each, seeds drawn
from ``numpy.random.SeedSequence([seed, pass])``), and the passes' moments are combined in
float64 (Chan et al.'s pairwise update), so neither memory nor float32 film accumulation
limits spp.
"""
from __future__ import annotations

import contextlib

import numpy as np

from bsdflab.reference import mitsuba_env
from bsdflab.reference.mitsuba_scene import path_integrator, to_mitsuba_scene
from bsdflab.reference.mitsuba_spectral import EDGES, sensor_bins
from bsdflab.reference.table_plugin import scene_uses_plugin, wavefront_mode
from bsdflab.render.scene import Scene
from bsdflab.util import args as check

MOMENTS_PLUGIN = "bsdflab_moments"
MAX_LANES = 1 << 20  # paths per mi.render call

_moment_variants: set[str] = set()


@contextlib.contextmanager
def use_variant(name: str | None):
    """Make ``name`` the reference variant for the duration (None: keep the usual one)."""
    if name is None or name == mitsuba_env.variant():
        yield
        return
    known = mitsuba_env.VARIANTS + mitsuba_env.SPECTRAL_VARIANTS
    if name not in known:
        raise ValueError(f"variant must be None or one of {', '.join(known)}, got {name!r}")
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
            c = _sensed_rgb(mi, spectrum, ray.wavelengths) if mi.is_spectral else mi.Color3f(spectrum)
            return spectrum, valid, [c.x, c.y, c.z, c.x * c.x, c.y * c.y, c.z * c.z]

        def aov_names(self):
            return ["m1.R", "m1.G", "m1.B", "m2.R", "m2.G", "m2.B"]

        def to_string(self):
            return f"MomentsIntegrator[nested={self.nested}]"

    mi.register_integrator(MOMENTS_PLUGIN, lambda props: MomentsIntegrator(props))
    _moment_variants.add(mi.variant())


def _sensed_rgb(mi, spectrum, wavelengths):
    """Our sensor's RGB score of a spectral sample (module doc): W / Δλ of the band each
    wavelength falls in, times L / p(λ), averaged over the sample's wavelengths."""
    import drjit as dr

    table = _sensor_tables(mi)
    value = mi.unpolarized_spectrum(spectrum) / mi.pdf_rgb_spectrum(wavelengths)
    rgb = [0.0, 0.0, 0.0]
    n = len(wavelengths)
    for j in range(n):
        lam = wavelengths[j]
        inside = (lam >= float(EDGES[0])) & (lam < float(EDGES[-1]))
        band = mi.UInt32(dr.clip((lam - float(EDGES[0])) / float(EDGES[1] - EDGES[0]), 0, len(EDGES) - 2))
        for r in range(3):
            w = dr.gather(mi.Float, table[r], band, inside) if dr.is_jit_v(mi.Float) else (
                table[r][int(band)] if inside else 0.0)
            rgb[r] = rgb[r] + w * value[j] / n
    return mi.Color3f(*rgb)


_tables: dict[str, list] = {}


def _sensor_tables(mi):
    """sensor_bins() rows as arrays Mitsuba's variant can gather from."""
    if mi.variant() not in _tables:
        rows = sensor_bins()
        _tables[mi.variant()] = [mi.Float(row) if hasattr(mi.Float, "__len__") else [float(x) for x in row]
                                 for row in rows]
    return _tables[mi.variant()]


def _check(scene, spp, seed) -> None:
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a bsdflab.render.Scene, got {type(scene).__name__}")
    if isinstance(spp, bool) or not isinstance(spp, (int, np.integer)) or not 2 <= spp <= 1 << 24:
        raise ValueError(f"spp must be an integer in [2, 2^24] (a variance needs 2 samples), got {spp!r}")
    check.integer("seed", seed, 0)


def _passes(spp: int, pixels: int) -> list[int]:
    per_pass = max(2, min(spp, MAX_LANES // max(pixels, 1)))
    count = -(-spp // per_pass)
    base, extra = divmod(spp, count)
    return [base + (k < extra) for k in range(count)]


def render_mitsuba(scene: Scene, spp: int, seed: int = 0, variant: str | None = None,
                   base_dir: str | None = None, bsdflab_fallback: bool = False,
                   cache_dir=None, spectral: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Render ``scene`` with Mitsuba 3's ``path`` integrator.

    Returns (mean, var_of_mean), both (H, W, 3) float64 linear sRGB: the box-filtered pixel
    means and the variance of each mean. variant: None for the reference variant
    (mitsuba_env.py), or 'llvm_ad_rgb' / 'scalar_rgb'. base_dir, bsdflab_fallback and
    cache_dir as in ``to_mitsuba_scene``. Scenes with the table plugin render in
    ``wavefront_mode`` (slower: one kernel per bounce). ``spectral=True``: the scene of our
    spectral mode in a spectral variant (default ``mitsuba_env.spectral_variant()``, or
    'llvm_ad_spectral' / 'scalar_spectral'), scored by our sensor (module doc).
    """
    _check(scene, spp, seed)
    spectral = check.flag("spectral", spectral)
    if spectral:
        variant = mitsuba_env.spectral_variant() if variant is None else variant
        if variant not in mitsuba_env.SPECTRAL_VARIANTS:
            raise ValueError(f"spectral=True needs variant None or one of "
                             f"{', '.join(mitsuba_env.SPECTRAL_VARIANTS)}, got {variant!r}")
    elif variant is not None and variant not in mitsuba_env.VARIANTS:
        raise ValueError(f"variant must be None or one of {', '.join(mitsuba_env.VARIANTS)}, got {variant!r}")
    with use_variant(variant):
        mi = mitsuba_env.mitsuba()
        _register_moments(mi)
        d = to_mitsuba_scene(scene, base_dir=base_dir, bsdflab_fallback=bsdflab_fallback,
                             cache_dir=cache_dir, spectral=bool(spectral))
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
