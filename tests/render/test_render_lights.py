"""Point, spot and directional lights (bsdflab/render/lights.py, core render_analytic_lights.cpp)
against closed forms, per pixel.

A camera looks straight down at a Lambertian plane (albedo rho) lit by one light, max_depth 2
(direct light only). A pixel's value is the mean over its area of

    point:        rho/pi * I cos(theta) / r^2
    spot:         rho/pi * I falloff(angle from the axis) cos(theta) / r^2   (Mitsuba 3's profile)
    directional:  rho/pi * E cos(theta)                        (also with an angular diameter
                                                                 whose cone stays above the horizon)

The reference integrates that over each pixel's footprint (16 x 16 midpoints through the
camera's own mapping). Delta lights make the render's only randomness the pixel jitter, so
its per-pixel variance is the noise the z-test uses; Sidak over all pixel-channels at
family-wise ALPHA = 1e-3, fixed seeds. Each closed-form test also shows power: the same
test must reject a slightly wrong closed form (the mutation named in its docstring).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from bsdflab.render import Camera, Environment, Material, Scene, Shape, render
from bsdflab.spectra import DEFAULT_WAVELENGTHS, rgb_to_spectrum, srgb_weights
from bsdflab.testing import image_z_test

ALPHA = 1e-3
RHO = 0.6
SIZE = 24
SPP = 64
SUB = 16  # midpoints per pixel side in the reference


def _plane_scene(lights, fov_deg=70.0, height=2.0, environment=None, shapes=()) -> Scene:
    plane = Shape({"type": "rectangle", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [40, 40]},
                  material="white", name="plane")
    camera = Camera(origin=(0.0, height, 0.0), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, -1.0), fov_deg=fov_deg,
                    width=SIZE, height=SIZE)
    return Scene(camera, (plane, *shapes), {"white": Material({"type": "diffuse", "reflectance": RHO})},
                 environment or Environment(), max_depth=2, lights=lights, name="lit-plane")


def _footprints(camera: Camera) -> np.ndarray:
    """(H, W, SUB*SUB, 3) plane points (y = 0) seen through each pixel's sub-pixel midpoints,
    by the camera mapping of core/include/bsdflab/render/camera.h."""
    o, t, up = (np.asarray(v, float) for v in (camera.origin, camera.target, camera.up))
    d = (t - o) / np.linalg.norm(t - o)
    left = np.cross(up, d)
    left /= np.linalg.norm(left)
    true_up = np.cross(d, left)
    tan_half = math.tan(math.radians(camera.fov_deg) / 2)
    w, h = camera.width, camera.height
    sub = (np.arange(SUB) + 0.5) / SUB
    x = (np.arange(w)[:, None] + sub[None, :]).ravel()
    y = (np.arange(h)[:, None] + sub[None, :]).ravel()
    sx = 1 - 2 * x / w
    sy = (1 - 2 * y / h) / (w / h)
    rays = (left * tan_half * sx[None, :, None] + true_up * tan_half * sy[:, None, None] + d)
    points = o - rays * (o[1] / rays[..., 1:2])
    return points.reshape(h, SUB, w, SUB, 3).transpose(0, 2, 1, 3, 4).reshape(h, w, SUB * SUB, 3)


def _pixel_means(camera: Camera, radiance) -> np.ndarray:
    """(H, W, 3): the mean of radiance(points) (..., 3) over each pixel's footprint."""
    return radiance(_footprints(camera)).mean(axis=2)


def _point_radiance(position, intensity, falloff=None):
    def radiance(p):
        to = np.asarray(position, float) - p
        r2 = np.sum(to * to, axis=-1)
        cos = to[..., 1] / np.sqrt(r2)
        f = 1.0 if falloff is None else falloff(-to / np.sqrt(r2)[..., None])
        return RHO / np.pi * (f * np.maximum(cos, 0) / r2)[..., None] * np.asarray(intensity, float)
    return radiance


def _mitsuba_falloff(axis, cutoff_deg, beam_deg):
    """Mitsuba 3's spot profile: 1 inside the beam width, linear in angle to 0 at the cutoff."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    cutoff, beam = math.radians(cutoff_deg), math.radians(beam_deg)

    def falloff(w):
        angle = np.arccos(np.clip(w @ a, -1, 1))
        return np.clip((cutoff - angle) / (cutoff - beam), 0.0, 1.0)
    return falloff


def _render(scene, spp=SPP, seed=0, **kwargs):
    r = render(scene, spp=spp, seed=seed, progress=False, **kwargs)
    return r.mean, r.variance


def _z_test(ours, expected):
    return image_z_test(ours[0], ours[1], expected, np.zeros_like(expected), alpha=ALPHA)


def test_01_point_light_over_a_lambertian_plane_is_inverse_square():
    """Per pixel, rho/pi I cos(theta)/r^2 with a coloured I. Power: the same render against
    I cos^2(theta)/r^2 (a wrong cosine) is rejected."""
    light = {"type": "point", "position": [0.3, 1.0, -0.2], "intensity": [2.0, 1.0, 0.5]}
    scene = _plane_scene([light])
    ours = _render(scene)
    expected = _pixel_means(scene.camera, _point_radiance(light["position"], light["intensity"]))
    result = _z_test(ours, expected)
    assert result.passed, result.summary()

    def wrong(p):
        to = np.asarray(light["position"]) - p
        cos = to[..., 1] / np.linalg.norm(to, axis=-1)
        return _point_radiance(light["position"], light["intensity"])(p) * cos[..., None]
    assert not _z_test(ours, _pixel_means(scene.camera, wrong)).passed


def test_02_spot_light_cone_edge_follows_mitsubas_linear_falloff():
    """A spot pointing straight down (cutoff 30 deg, beam width 20 deg) draws a disc whose
    rim falls linearly in angle, per pixel. Power: a cutoff of 29 deg, or a smoothstep
    profile between the same angles, is rejected."""
    light = {"type": "spot", "position": [0.0, 1.0, 0.0], "direction": [0.0, -1.0, 0.0], "intensity": 3.0,
             "cutoff_angle_deg": 30.0, "beam_width_deg": 20.0}
    scene = _plane_scene([light], fov_deg=70.0)
    ours = _render(scene)
    axis = light["direction"]
    expected = _pixel_means(scene.camera, _point_radiance(light["position"], [3.0] * 3,
                                                          _mitsuba_falloff(axis, 30.0, 20.0)))
    assert expected[SIZE // 2, SIZE // 2, 0] > 0 and expected[0, 0, 0] == 0  # the edge is in view
    result = _z_test(ours, expected)
    assert result.passed, result.summary()
    narrower = _pixel_means(scene.camera, _point_radiance(light["position"], [3.0] * 3,
                                                          _mitsuba_falloff(axis, 29.0, 20.0)))
    assert not _z_test(ours, narrower).passed
    linear = _mitsuba_falloff(axis, 30.0, 20.0)

    def smooth(w):
        t = linear(w)
        return t * t * (3 - 2 * t)
    smoothstep = _pixel_means(scene.camera, _point_radiance(light["position"], [3.0] * 3, smooth))
    assert not _z_test(ours, smoothstep).passed


def test_03_directional_light_gives_rho_over_pi_e_cos_exactly():
    """Deterministic: every sample of every pixel is rho/pi E cos(theta) (no noise), so the
    image must equal it to float precision. Power: the tolerance is 1e-9 relative."""
    theta = math.radians(40.0)
    light = {"type": "directional", "direction": [math.sin(theta), -math.cos(theta), 0.0],
             "irradiance": [1.5, 1.0, 0.25]}
    ours, var = _render(_plane_scene([light]))
    expected = RHO / np.pi * math.cos(theta) * np.array([1.5, 1.0, 0.25])
    np.testing.assert_allclose(ours, np.broadcast_to(expected, ours.shape), rtol=1e-9, atol=0)
    assert np.all(var <= 1e-15 * ours**2)  # round-off of the variance sums only


@pytest.mark.parametrize("strategy", ["mis", "light", "bsdf"])
def test_04_soft_sun_irradiance_is_that_of_its_direction(strategy):
    """A directional light with a 40 deg angular diameter, 35 deg from the normal: its cone
    stays above the horizon, so the plane's radiance is still rho/pi E cos(theta) (a uniform
    cap of half angle a gives irradiance L pi sin^2(a) cos(theta)). Each strategy alone is
    unbiased and MIS combines them (BSDF rays find the cone when they leave the scene; they
    hit it rarely, so that strategy is tested over 4 x 4 blocks). Power: 5 % more light is
    rejected over 8 x 8 blocks."""
    theta = math.radians(35.0)
    light = {"type": "directional", "direction": [0.0, -math.cos(theta), math.sin(theta)],
             "irradiance": [1.0, 0.8, 0.6], "angular_diameter_deg": 40.0}
    scene = _plane_scene([light])
    ours = _render(scene, spp=2048 if strategy == "bsdf" else 256, strategy=strategy)
    block = 4 if strategy == "bsdf" else 1
    expected = np.ascontiguousarray(np.broadcast_to(
        RHO / np.pi * math.cos(theta) * np.array([1.0, 0.8, 0.6]), ours[0].shape))
    zero = np.zeros_like(expected)
    result = image_z_test(*ours, expected, zero, alpha=ALPHA, block=block)
    assert result.passed, result.summary()
    assert not image_z_test(*ours, 1.05 * expected, zero, alpha=ALPHA, block=8).passed


def test_05_mixed_lights_equal_the_sum_of_each_alone():
    """An area light, an environment, a point, a spot and a soft sun in one scene (MIS with
    the light-selection probabilities in every density) against the sum of five renders
    with one light each: light transport is linear, so the expectations are equal. Power:
    the sum with the point, the spot or the sun at half weight is rejected."""
    area = Shape({"type": "rectangle", "center": [0.8, 1.2, 0.0], "normal": [0, -1, 0], "size": [0.4, 0.4]},
                 emission=(6.0, 6.0, 6.0), name="lamp")
    ball = Shape({"type": "sphere", "center": [-0.3, 0.35, 0.2], "radius": 0.35, "subdivisions": 24},
                 material="white", name="ball")
    point = {"type": "point", "position": [-0.6, 1.0, -0.5], "intensity": [1.0, 0.5, 0.2]}
    spot = {"type": "spot", "position": [0.0, 1.5, 0.6], "direction": [0.0, -1.0, -0.4], "intensity": 2.0,
            "cutoff_angle_deg": 25.0}
    sun = {"type": "directional", "direction": [0.3, -1.0, 0.2], "irradiance": 0.7, "angular_diameter_deg": 6.0}
    env = Environment("constant", radiance=(0.1, 0.15, 0.25))
    depth = 3

    def scene(lights, with_area, with_env):  # the lamp is always there (it casts shadows), lit or not
        lamp = area if with_area else replace(area, emission=(0.0, 0.0, 0.0))
        s = _plane_scene(lights, fov_deg=60.0, environment=env if with_env else None, shapes=(ball, lamp))
        return replace(s, max_depth=depth).with_resolution(16, 16)

    mixed = _render(scene([point, spot, sun], True, True), spp=256, seed=1)
    parts = [_render(scene([], True, False), spp=256, seed=2), _render(scene([], False, True), spp=256, seed=3),
             _render(scene([point], False, False), spp=256, seed=4),
             _render(scene([spot], False, False), spp=256, seed=5),
             _render(scene([sun], False, False), spp=256, seed=6)]
    total = sum(p[0] for p in parts), sum(p[1] for p in parts)
    result = image_z_test(*mixed, *total, alpha=ALPHA, block=2)
    assert result.passed, result.summary()
    for k in range(2, 5):  # a point, spot or sun left at half weight (e.g. a selection probability lost)
        halved = total[0] - 0.5 * parts[k][0], total[1]
        assert not image_z_test(*mixed, *halved, alpha=ALPHA, block=2).passed, k


def test_06_spectral_point_light_is_the_lifted_spectrum_through_the_sensor():
    """Spectral mode: the point light's RGB is lifted (Mallett-Yuksel U) and the pixel is
    W (U I) rho/pi cos/r^2 on the grey plane. Power: 2 % more light is rejected."""
    light = {"type": "point", "position": [0.0, 1.2, 0.0], "intensity": [0.3, 1.0, 2.0]}
    scene = _plane_scene([light])
    ours = _render(scene, spectral=True)
    wl = DEFAULT_WAVELENGTHS
    sensed = srgb_weights(wl) @ rgb_to_spectrum(np.asarray(light["intensity"]), wl)
    expected = _pixel_means(scene.camera, _point_radiance(light["position"], sensed))
    result = _z_test(ours, expected)
    assert result.passed, result.summary()
    assert not _z_test(ours, 1.02 * expected).passed


def test_07_delta_lights_are_never_found_by_bsdf_sampling():
    """BSDF sampling alone cannot hit a point, a spot or a sharp directional light: the image
    is black, and a camera looking at a point light does not see it."""
    lights = [{"type": "point", "position": [0.0, 1.0, 0.0], "intensity": 5.0},
              {"type": "spot", "position": [0.0, 1.0, 0.0], "direction": [0, -1, 0], "intensity": 5.0},
              {"type": "directional", "direction": [0, -1, 0], "irradiance": 5.0}]
    mean, _ = _render(_plane_scene(lights), spp=4, strategy="bsdf")
    assert np.all(mean == 0)
    mean, _ = _render(replace(_plane_scene(lights), max_depth=1), spp=4)
    assert np.all(mean == 0)


@pytest.mark.parametrize("light, match", [
    ({"type": "point", "position": [0, 1, 0], "intensity": -1.0}, "intensity"),
    ({"type": "point", "position": [0, 1, 0], "intensity": float("nan")}, "intensity"),
    ({"type": "point", "position": [0, float("inf"), 0], "intensity": 1.0}, "position"),
    ({"type": "point", "intensity": 1.0}, "position is required"),
    ({"type": "point", "position": [True, 1, 0], "intensity": 1.0}, "position"),
    ({"type": "directional", "direction": [0, -1, False], "irradiance": 1.0}, "direction"),
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 1, "cutoff_angle_deg": 0},
     "cutoff_angle_deg"),
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 1, "cutoff_angle_deg": 20,
      "beam_width_deg": 25}, "beam_width_deg"),
    ({"type": "spot", "position": [0, 1, 0], "direction": [0, 0, 0], "intensity": 1}, "direction"),
    ({"type": "directional", "direction": [0, 0, 0], "irradiance": 1.0}, "direction"),
    ({"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 2]}, "irradiance"),
    ({"type": "directional", "direction": [0, -1, 0], "irradiance": 1, "angular_diameter_deg": -1},
     "angular_diameter_deg"),
    ({"type": "directional", "direction": [0, -1, 0], "irradiance": 1, "intensity": 1}, "intensity"),
    ({"type": "sun", "turbidity": 20}, "turbidity"),
    ({"type": "sun", "elevation_deg": -5}, "elevation_deg"),
    ({"type": "laser"}, "unknown light type"),
    ("point", "must be a dict"),
])
def test_08_bad_light_parameters_raise_value_error_naming_the_field(light, match):
    d = _plane_scene([{"type": "point", "position": [0, 1, 0], "intensity": 1.0}]).to_dict()
    d["lights"] = [light]
    with pytest.raises(ValueError, match=match):
        Scene.from_dict(d)


def test_09_scene_dict_round_trip_with_lights_and_lights_count_as_light():
    lights = [{"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 1.0},
              {"type": "sun", "elevation_deg": 20.0, "name": "noon"}]
    scene = _plane_scene(lights)
    again = Scene.from_dict(scene.to_dict())
    assert again == scene
    assert again.lights[0].beam_width_deg == pytest.approx(15.0)  # Mitsuba's default: 3/4 of the cutoff
    assert "lights" not in replace(scene, lights=(), environment=Environment("constant")).to_dict()


def test_10_a_spectral_light_colour_multiplies_a_spectral_reflectance_bin_by_bin():
    """A point light whose intensity is a spectrum (rising towards the red) over a plane whose
    diffuse reflectance is a narrow band at 600 nm: spectral mode gives sum_l W_l v_l r_l / pi
    x cos/r^2 per pixel, the bins multiplied as they are. Power: the same render against the
    lift of the light's RGB (W U (W v)), what spectral mode did before lights could carry a
    spectrum, is rejected."""
    wl = DEFAULT_WAVELENGTHS
    v = np.linspace(0.2, 1.8, len(wl))
    band = np.exp(-0.5 * ((wl - 600.0) / 15.0) ** 2)
    light = {"type": "point", "position": [0.2, 1.0, 0.0],
             "intensity": {"type": "tabulated", "wavelengths": wl.tolist(), "values": (3.0 * v).tolist()}}
    reflectance = {"type": "tabulated", "wavelengths": wl.tolist(), "values": band.tolist()}
    scene = _plane_scene([light])
    scene = replace(scene, materials={"white": Material({"type": "diffuse", "reflectance": reflectance})})
    ours = _render(scene, spectral=True)
    W = srgb_weights(wl)

    def expected_for(spectrum):
        colour = W @ (spectrum * band) / RHO  # _point_radiance multiplies by RHO
        return _pixel_means(scene.camera, _point_radiance(light["position"], colour))
    result = _z_test(ours, expected_for(3.0 * v))
    assert result.passed, result.summary()
    lifted = rgb_to_spectrum(W @ (3.0 * v), wl)
    assert not _z_test(ours, expected_for(lifted)).passed
    rgb_mode = _render(scene)  # RGB mode: the light's RGB, W v
    assert np.all(np.isfinite(rgb_mode[0])) and rgb_mode[0].max() > 0


@pytest.mark.parametrize("diameter_deg", [1e-100, 1e-300])
def test_11_a_vanishing_angular_diameter_is_the_sharp_directional_light(diameter_deg):
    """A soft sun far narrower than its density can represent (1/(2 pi (1 - cos a)) overflows
    when squared by the power heuristic at 1e-100 deg, and is infinite at 1e-300 deg) must
    render as the sharp directional light, rho/pi E cos(theta) to float precision, with no
    invalid samples. Regression: every sample was NaN, dropped, and the image black."""
    theta = math.radians(30.0)
    light = {"type": "directional", "direction": [math.sin(theta), -math.cos(theta), 0.0],
             "irradiance": [1.5, 1.0, 0.25], "angular_diameter_deg": diameter_deg}
    r = render(_plane_scene([light]).with_resolution(8, 8), spp=4, seed=0, progress=False)
    expected = RHO / np.pi * math.cos(theta) * np.array([1.5, 1.0, 0.25])
    assert r.invalid_samples == 0
    np.testing.assert_allclose(r.mean, np.broadcast_to(expected, r.mean.shape), rtol=1e-9, atol=0)


def test_12_a_wide_soft_sun_among_other_strategies_is_weighted_by_its_selection():
    """A soft sun of 80 deg diameter straight overhead (its cone inside the plane's
    hemisphere: radiance rho/pi E), a point light and a constant environment (the plane sees
    all of its upper hemisphere: rho L_env): three NEE strategies, so the density MIS gives
    a BSDF-sampled ray that finds the sun must be the cone's 1/(2 pi (1 - cos a)) times the
    selection probability 1/3, as next-event estimation's. The cone is wide enough for the
    BSDF strategy to matter. Power: with the selection left out of the sun's hit density
    (RenderScene::soft_light) the weights no longer sum to 1 and the image is ~30 % dark
    (every pixel rejected; tests 04 and 05 pass that mutant); 5 % more light is rejected
    over 4 x 4 blocks."""
    sun = {"type": "directional", "direction": [0.0, -1.0, 0.0], "irradiance": [1.0, 0.8, 0.6],
           "angular_diameter_deg": 80.0}
    point = {"type": "point", "position": [0.3, 1.0, -0.2], "intensity": [0.5, 0.4, 0.3]}
    env = (0.2, 0.25, 0.3)
    scene = _plane_scene([sun, point], environment=Environment("constant", radiance=env))
    ours = _render(scene, spp=256)
    expected = (_pixel_means(scene.camera, _point_radiance(point["position"], point["intensity"]))
                + RHO / np.pi * np.array(sun["irradiance"]) + RHO * np.array(env))
    result = _z_test(ours, expected)
    assert result.passed, result.summary()
    assert not image_z_test(*ours, 1.05 * expected, np.zeros_like(expected), alpha=ALPHA, block=4).passed


def test_13_a_large_area_light_among_analytic_lights_is_weighted_by_its_selection():
    """A large, near area light (a wall beside the plane), a constant environment and a
    point light against the sum of three renders with one of them lit each (linearity, as
    test 05). The lamp is large and close, so BSDF-sampled rays find it often and its MIS
    density on a hit (RenderScene::emitter_pdf) matters. Power: that density without the
    area-light selection probability 1/3 (a mutant tests 04, 05 and 12 pass) is rejected,
    and so is the sum with the lamp at 95 %."""
    lamp = Shape({"type": "rectangle", "center": [1.0, 0.5, 0.0], "normal": [-1, 0, 0], "size": [1.0, 3.0]},
                 emission=(1.5, 1.4, 1.2), name="lamp")
    point = {"type": "point", "position": [-0.4, 0.8, 0.3], "intensity": [0.6, 0.5, 0.4]}
    env = Environment("constant", radiance=(0.1, 0.15, 0.25))

    def scene(lights, lit, with_env):  # the lamp is always there (it casts shadows), lit or not
        shape = lamp if lit else replace(lamp, emission=(0.0, 0.0, 0.0))
        s = _plane_scene(lights, fov_deg=60.0, environment=env if with_env else None, shapes=(shape,))
        return s.with_resolution(16, 16)

    mixed = _render(scene([point], True, True), spp=256, seed=1)
    parts = [_render(scene([], True, False), spp=256, seed=2), _render(scene([], False, True), spp=256, seed=3),
             _render(scene([point], False, False), spp=256, seed=4)]
    total = sum(p[0] for p in parts), sum(p[1] for p in parts)
    result = image_z_test(*mixed, *total, alpha=ALPHA, block=2)
    assert result.passed, result.summary()
    dimmer = total[0] - 0.05 * parts[0][0], total[1]
    assert not image_z_test(*mixed, *dimmer, alpha=ALPHA, block=2).passed


def test_14_spectral_mode_lights_with_the_suns_own_spectrum():
    """A sharp sun (no sky) 20 deg above a plane whose reflectance is a narrow band at
    450 nm: spectral mode must use the sun's spectrum after the atmosphere (a 5778 K black
    body times Preetham's Rayleigh and aerosol transmittance, relative to D65, at the
    transmitted illuminance), so the pixel is sin(20 deg)/pi sum_l W_l s_l r_l exactly
    (a delta light: no noise). Power: the lift of the sun's RGB, what spectral mode used
    before, is off by several per cent and fails the 1e-9 tolerance."""
    import colour

    from bsdflab.render.sky import sun_transmittance

    elevation, turbidity, scale = 20.0, 3.0, 0.01
    wl = DEFAULT_WAVELENGTHS
    band = np.exp(-0.5 * ((wl - 450.0) / 12.0) ** 2)
    sun = {"type": "sun", "elevation_deg": elevation, "turbidity": turbidity, "scale": scale,
           "angular_diameter_deg": 0.0, "sky": False}
    scene = replace(_plane_scene([sun]).with_resolution(4, 4),
                    materials={"white": Material({"type": "diffuse", "reflectance": {
                        "type": "tabulated", "wavelengths": wl.tolist(), "values": band.tolist()}})})
    r = render(scene, spp=2, seed=0, progress=False, spectral=True)
    # the expected spectrum, built here from its definition on the renderer's bins
    shape = colour.SpectralShape(360, 830, 1)
    on_bins = np.searchsorted(np.arange(360.0, 831.0), wl)
    body = colour.sd_blackbody(5778.0, shape).values[on_bins]
    ybar = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values[on_bins, 1]
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape).values[on_bins]
    through = sun_transmittance(wl, math.radians(90.0 - elevation), turbidity)
    klx = 128.0 * np.sum(ybar * body * through) / np.sum(ybar * body)
    W = srgb_weights(wl)
    s = body * through / d65
    s *= scale * klx / (np.array([0.2126, 0.7152, 0.0722]) @ (W @ s))
    expected = math.sin(math.radians(elevation)) / np.pi * (W @ (s * band))
    np.testing.assert_allclose(r.mean, np.broadcast_to(expected, r.mean.shape), rtol=1e-9, atol=0)


def test_15_lit_images_do_not_depend_on_thread_count_and_repeat_per_seed(tmp_path):
    """Every kind of light at once (point, spot, soft sun, area lamp, environment), 40 x 40
    pixels (9 tiles, so 2 threads really split each pass), RGB and spectral: the same images
    with 1 and 2 threads and for a repeated seed, bit for bit; another seed gives others."""
    import json

    from support.thread_images import images_per_thread_count

    lamp = Shape({"type": "rectangle", "center": [0.8, 1.2, 0.0], "normal": [0, -1, 0], "size": [0.4, 0.4]},
                 emission=(6.0, 6.0, 6.0), name="lamp")
    lights = [{"type": "point", "position": [-0.6, 1.0, -0.5], "intensity": [1.0, 0.5, 0.2]},
              {"type": "spot", "position": [0.0, 1.5, 0.6], "direction": [0.0, -1.0, -0.4], "intensity": 2.0},
              {"type": "directional", "direction": [0.3, -1.0, 0.2], "irradiance": 0.7,
               "angular_diameter_deg": 6.0}]
    scene = replace(_plane_scene(lights, environment=Environment("constant", radiance=(0.1, 0.15, 0.25)),
                                 shapes=(lamp,)), max_depth=4).with_resolution(40, 40)

    def images(seed):
        return np.stack([render(scene, spp=2, seed=seed, progress=False, spectral=m).mean for m in (False, True)])

    text = json.dumps(scene.to_dict())
    one = "render(Scene.from_dict(json.loads(" + repr(text) + ")), spp=2, seed=5, progress=False, spectral=MODE).mean"
    expr = f"np.stack([{one.replace('MODE', 'False')}, {one.replace('MODE', 'True')}])"
    out = images_per_thread_count(tmp_path, "import json; from bsdflab.render import Scene, render", expr)
    assert np.array_equal(out["1"], out["2"])
    again = images(5)
    assert np.array_equal(again, out["1"])
    other = images(6)
    assert not np.array_equal(other[0], again[0]) and not np.array_equal(other[1], again[1])
