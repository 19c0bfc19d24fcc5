"""A film whose indices do not depend on the wavelength (guanine on keratin, the snake's
iridophores) is evaluated with its angular part shared by all channels (issue 21: the
film was ~70 % of a snake walk). Each case below checks the shared path against the
per-wavelength stack (`film_stack`, itself checked against tmm in tests/optics) at every
channel: exactly where the same operations run, to rounding where one lossless film takes
the Airy sum's closed form (R = (a + b cos 2δ) / (d + b cos 2δ), T = 1 − R)."""
import numpy as np
import pytest

from bsdflab import _core

WL = np.linspace(380.0, 780.0, 81)


def term(ext, layers, thick, sub, transmits=True, wl=WL):
    """A FilmTerm with per-channel index lists (a scalar index is repeated)."""
    per_channel = lambda n: list(np.broadcast_to(np.asarray(n, dtype=complex), wl.shape))  # noqa: E731
    return _core.FilmTerm(list(wl), ext, [per_channel(n) for n in layers], list(thick), per_channel(sub),
                          transmits)


def reference(ext, layers, thick, sub, cos_i, transmits=True, wl=WL, scale=1.0):
    """(R, T) per channel from film_stack, one wavelength per row, as FilmTerm defines them."""
    per_channel = [np.broadcast_to(np.asarray(x, dtype=complex), wl.shape) for x in [ext, *layers, sub]]
    n = np.stack(per_channel, axis=1)                      # (channels, media) in the order from above
    d = np.tile(np.asarray(thick, dtype=float) * scale, (len(wl), 1)).reshape(len(wl), len(thick))
    if cos_i < 0:                                          # from below: the media met in reverse
        n, d = n[:, ::-1], d[:, ::-1]
    out = _core.film_stack(n, d, np.full(len(wl), abs(cos_i)), wl)
    R = 0.5 * (out[4] + out[5])
    T = 0.5 * (out[6] + out[7]) if transmits else np.zeros_like(R)
    R = np.clip(R, 0.0, 1.0)
    return R, np.clip(T, 0.0, 1.0 - R)


COSINES = [1.0, 0.83, 0.5, 0.21, 0.03, 1e-6, -1.0, -0.9, -0.75, -0.6, -0.3, -0.05]


@pytest.mark.parametrize("ext,n1,sub,d", [
    (1.000277, 1.83, 1.5515, 400.0),   # the snake: air | guanine | keratin
    (1.0, 1.33, 1.5, 1200.0),          # a film below the substrate's index
    (1.5, 2.4, 1.0, 95.0),             # a dense film on a rarer substrate
    (1.0, 1.83, 1.5515, 0.0),          # zero thickness: the bare interface
])
def test_lossless_film_closed_form_matches_the_stack(ext, n1, sub, d):
    t = term(ext, [n1], [d], sub)
    for c in COSINES:
        R, T = (np.asarray(v) for v in t.eval(c))
        R0, T0 = reference(ext, [n1], [d], sub, c)
        # R and T lie in [0, 1]: an absolute tolerance of a few ulps of 1 (rtol=0).
        assert np.allclose(R, R0, rtol=0, atol=2e-14), (c, np.max(np.abs(R - R0)))
        assert np.allclose(T, T0, rtol=0, atol=2e-14), (c, np.max(np.abs(T - T0)))


@pytest.mark.parametrize("ext,layers,thick,sub,transmits", [
    (1.0, [1.83 + 0.02j], [300.0], 1.5515, True),                 # absorbing film
    (1.0, [1.83, 1.33] * 4 + [1.83], [80.0, 100.0] * 4 + [80.0], 1.5515, True),  # iridophore stack
    (1.0, [1.38], [110.0], 0.2 + 3.0j, False),                    # film on a conductor
    (1.0, [], [], 1.5, True),                                     # no layer at all
])
def test_other_uniform_stacks_equal_the_stack_exactly(ext, layers, thick, sub, transmits):
    t = term(ext, layers, thick, sub, transmits)
    for c in COSINES:
        R, T = (np.asarray(v) for v in t.eval(c))
        if c < 0 and not transmits:
            assert not R.any() and not T.any()
            continue
        R0, T0 = reference(ext, layers, thick, sub, c, transmits)
        # The same operations in the same order: bit for bit.
        assert np.array_equal(R, R0) and np.array_equal(T, T0), c


def test_thickness_override_scales_the_shared_path():
    t = term(1.0, [1.83, 1.33, 1.83], [80.0, 100.0, 80.0], 1.5515)
    R, T = (np.asarray(v) for v in t.eval(0.7, 520.0))
    R0, T0 = reference(1.0, [1.83, 1.33, 1.83], [80.0, 100.0, 80.0], 1.5515, 0.7, scale=520.0 / 260.0)
    assert np.array_equal(R, R0) and np.array_equal(T, T0)


def test_dispersive_film_keeps_the_per_channel_path():
    n1 = 1.8 + 2e4 / WL**2  # a Cauchy film: every channel its own index
    t = term(1.0, [n1], [400.0], 1.55)
    for c in (0.9, -0.4):
        R, T = (np.asarray(v) for v in t.eval(c))
        R0, T0 = reference(1.0, [n1], [400.0], 1.55, c)
        assert np.array_equal(R, R0) and np.array_equal(T, T0)


def test_grazing_and_non_finite_cosines():
    t = term(1.000277, [1.83], [400.0], 1.5515)
    R, T = (np.asarray(v) for v in t.eval(0.0))
    assert np.array_equal(R, np.ones_like(R)) and not T.any()
    for bad in (np.nan, np.inf, -np.inf):
        R, T = (np.asarray(v) for v in t.eval(bad))
        assert np.all(np.isfinite(R)) and np.all(np.isfinite(T))
        assert np.all((R >= 0) & (R <= 1) & (T >= 0) & (R + T <= 1 + 1e-15))


# Found by review: the closed form's denominator 1 + p² + 2p cos 2δ (p = r01 r12) cancels to
# (1 − |p|)² as |p| → 1, a film between equal media at grazing incidence: |T − T_stack| was
# 3e-6, 3e-4, 3e-2 at cos 1e-6, 1e-7, 1e-8 near a resonance, and a zero-thickness film at
# cos ≤ 3e-9 read R = T = 0 (0/0, clamped: the light vanished). Such films take the fold.
@pytest.mark.parametrize("cos", [1e-6, 1e-7, 1e-8, -1e-8])
def test_film_between_equal_media_at_grazing_incidence(cos):
    n0, n1 = 1.33, 1.83  # a guanine platelet in cytoplasm
    z = abs(cos)
    q0, q1 = n0 * z, np.sqrt(n1**2 - n0**2 * (1 - z * z))
    r = (q0 - q1) / (q0 + q1)
    d0 = 3 * 500.0 / (2 * q1)  # 2δ = 6π at 500 nm: a transmission resonance
    wl = 500.0 * (1 + np.linspace(-3, 3, 61) * (1 - r * r) / abs(r) / (6 * np.pi))  # across it
    t = term(n0, [n1], [d0], n0, wl=wl)
    R, T = (np.asarray(v) for v in t.eval(cos))
    R0, T0 = reference(n0, [n1], [d0], n0, cos, wl=wl)
    assert np.allclose(R, R0, rtol=0, atol=1e-12) and np.allclose(T, T0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("cos", [1e-9, 1e-12, -1e-9])
def test_zero_thickness_film_between_equal_media_passes_everything(cos):
    for t, thickness in ((term(1.0, [1.33], [0.0], 1.0), -1.0), (term(1.0, [1.33], [500.0], 1.0), 0.0)):
        R, T = (np.asarray(v) for v in t.eval(cos, thickness))
        assert np.all(T > 0.999) and np.all(R < 1e-3), (cos, thickness, R[:3], T[:3])
