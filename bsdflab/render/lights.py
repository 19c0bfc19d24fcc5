"""Lights without geometry: what a scene's ``lights`` list holds, validated.

    {"type": "point", "position": [x, y, z], "intensity": I}
    {"type": "spot", "position": ..., "direction": ..., "intensity": I,
     "cutoff_angle_deg": 20, "beam_width_deg": 15}
    {"type": "directional", "direction": ..., "irradiance": E, "angular_diameter_deg": 0}
    {"type": "sun", "elevation_deg": 35, "azimuth_deg": 0, "turbidity": 3, "scale": 0.05,
     "angular_diameter_deg": 0.53, "sky": true}

Units and conventions are Mitsuba 3's (``point``, ``spot``, ``directional``): intensity in
W/sr, irradiance in W/m^2 on a surface facing the light, colours linear sRGB (one number
or three) or a spectrum dict (bsdflab.spectra.Spectrum: spectral mode uses its bins as
they are -- relative to the sensor's D65, as every spectrum in the renderer, so a flat 1
is white --, RGB mode their RGB); a spot shines along ``direction`` with Mitsuba's profile (full intensity inside
``beam_width_deg``, falling linearly in angle to 0 at ``cutoff_angle_deg``; default beam
width 3/4 of the cutoff, as Mitsuba); a directional light's ``direction`` is the way its
light travels. ``angular_diameter_deg`` > 0 makes a soft sun: the same irradiance from a
cone of directions of constant radiance.

``sun`` is a preset: a soft directional light (diameter 0.53 deg) whose colour and
illuminance come from the sun's spectrum through the atmosphere, and, with ``sky``, the
Preetham et al. (1999) sky for the same sun and turbidity as the environment
(bsdflab/render/sky.py; it replaces the scene's own environment). ``elevation_deg`` above
the horizon, ``azimuth_deg`` about +Y (0: the sun is towards +Z, 90: towards +X).

Every value is checked here: a bad one raises ValueError naming the light and the field.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from bsdflab.util.args import brief, flag, real_scalar

LIGHT_TYPES = ("point", "spot", "directional", "sun")
MAX_VALUE = 1e12
SUN_DIAMETER_DEG = 0.53  # the sun's mean angular diameter seen from the Earth
# Which fields each type takes (besides type and name), with their defaults.
_FIELDS: dict[str, dict[str, Any]] = {
    "point": {"position": None, "intensity": None},
    "spot": {"position": None, "direction": None, "intensity": None, "cutoff_angle_deg": 20.0,
             "beam_width_deg": None},
    "directional": {"direction": None, "irradiance": None, "angular_diameter_deg": 0.0},
    "sun": {"elevation_deg": 35.0, "azimuth_deg": 0.0, "turbidity": 3.0, "scale": 0.05,
            "angular_diameter_deg": SUN_DIAMETER_DEG, "sky": True},
}
_REQUIRED = {"point": ("position", "intensity"), "spot": ("position", "direction", "intensity"),
             "directional": ("direction", "irradiance"), "sun": ()}


def _colour(name: str, value: Any) -> tuple[float, float, float] | dict:
    if isinstance(value, dict):
        return _spectrum(name, value)
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a number or 3 numbers, got {brief(value)}") from None
    if isinstance(value, (str, bytes, bool)) or a.ndim > 1 or a.size not in (1, 3):
        raise ValueError(f"{name} must be a number or 3 numbers, got {brief(value)}")
    a = np.broadcast_to(a.ravel(), (3,)) if a.size == 1 else a
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {brief(value)}")
    if np.any(a < 0) or np.any(a > MAX_VALUE):
        raise ValueError(f"{name} must be in [0, {MAX_VALUE:g}], got {brief(value)}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _spectrum(name: str, value: dict) -> dict:
    """A spectral colour: a bsdflab spectrum dict (``{"type": "tabulated", "wavelengths": [...],
    "values": [...]}``, "constant" or "rgb"), checked on the renderer's wavelength grid."""
    from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum

    try:
        spectrum = Spectrum.from_dict(value)
        values = np.asarray(spectrum.at(DEFAULT_WAVELENGTHS), dtype=float)
    except (TypeError, KeyError) as e:
        raise ValueError(f"{name}: not a spectrum dict ({e})") from None
    except ValueError as e:
        raise ValueError(f"{name}: {e}") from None
    if not np.all(np.isfinite(values)) or np.any(values < 0) or np.any(values > MAX_VALUE):
        raise ValueError(f"{name} must be finite and in [0, {MAX_VALUE:g}] at every wavelength")
    return spectrum.to_dict()


def colour_of(value) -> tuple[list[float], list[float]]:
    """(RGB, spectrum) the renderer gets for a light's colour: an RGB triple and no spectrum
    (spectral mode lifts the RGB), or a spectrum's 81 bins and their RGB (W v, clipped to
    >= 0: a spectrum outside the sRGB gamut is clipped in RGB mode only)."""
    if not isinstance(value, dict):
        return list(value), []
    from bsdflab.spectra import DEFAULT_WAVELENGTHS, Spectrum, srgb_weights

    bins = np.asarray(Spectrum.from_dict(value).at(DEFAULT_WAVELENGTHS), dtype=float)
    rgb = np.maximum(srgb_weights(DEFAULT_WAVELENGTHS) @ bins, 0.0)
    return rgb.tolist(), bins.tolist()


def _point(name: str, value: Any) -> tuple[float, float, float]:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be 3 finite numbers, got {brief(value)}") from None
    flags = isinstance(value, (list, tuple)) and any(isinstance(x, (bool, np.bool_)) for x in value)
    if isinstance(value, (str, bytes)) or flags or a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be 3 finite numbers, got {brief(value)}")
    if np.abs(a).max() > 1e15:
        raise ValueError(f"{name} must be within 1e15 of the origin, got {brief(value)}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _direction(name: str, value: Any) -> tuple[float, float, float]:
    a = _point(name, value)
    n = math.sqrt(sum(x * x for x in a))
    if not n > 1e-12 * max(1.0, max(abs(x) for x in a)):
        raise ValueError(f"{name} must not have length 0, got {brief(value)}")
    return a


@dataclass(frozen=True)
class Light:
    """One light of a scene's ``lights`` list (module doc). Fields a type does not take
    stay None; ``from_dict`` fills the type's defaults."""

    type: str
    position: tuple[float, float, float] | None = None
    direction: tuple[float, float, float] | None = None
    intensity: tuple[float, float, float] | dict | None = None
    irradiance: tuple[float, float, float] | dict | None = None
    cutoff_angle_deg: float | None = None
    beam_width_deg: float | None = None
    angular_diameter_deg: float | None = None
    elevation_deg: float | None = None
    azimuth_deg: float | None = None
    turbidity: float | None = None
    scale: float | None = None
    sky: bool | None = None
    name: str = ""

    def __post_init__(self):
        if self.type not in LIGHT_TYPES:
            raise ValueError(f"unknown light type {brief(self.type)}; known: {', '.join(LIGHT_TYPES)}")
        label = f"light {self.name!r} ({self.type})" if self.name else f"{self.type} light"
        taken = _FIELDS[self.type]
        for f in fields(self):
            if f.name in ("type", "name"):
                continue
            value = getattr(self, f.name)
            if f.name not in taken:
                if value is not None:
                    raise ValueError(f"{label}: a {self.type} light has no {f.name!r}; "
                                     f"it takes: {', '.join(taken)}")
                continue
            if value is None:
                if f.name in _REQUIRED[self.type]:
                    raise ValueError(f"{label}: {f.name} is required")
                value = taken[f.name]
            object.__setattr__(self, f.name, self._checked(label, f.name, value))
        if self.type == "spot":
            if self.beam_width_deg is None:
                object.__setattr__(self, "beam_width_deg", 0.75 * self.cutoff_angle_deg)
            elif self.beam_width_deg > self.cutoff_angle_deg:
                raise ValueError(f"{label}: beam_width_deg must be <= cutoff_angle_deg "
                                 f"({self.cutoff_angle_deg:g}), got {self.beam_width_deg:g}")
        if not isinstance(self.name, str):
            raise ValueError(f"light name must be a string, got {brief(self.name)}")

    def _checked(self, label: str, name: str, value: Any):
        field_name = f"{label}: {name}"
        if name in ("intensity", "irradiance"):
            return _colour(field_name, value)
        if name == "position":
            return _point(field_name, value)
        if name == "direction":
            return _direction(field_name, value)
        if name == "cutoff_angle_deg":
            return real_scalar(field_name, value, 0.0, 90.0, lo_open=True)
        if name == "beam_width_deg":
            return None if value is None else real_scalar(field_name, value, 0.0, 90.0, lo_open=True)
        if name == "angular_diameter_deg":
            return real_scalar(field_name, value, 0.0, 90.0, hi_open=True)
        if name == "elevation_deg":
            return real_scalar(field_name, value, 0.0, 90.0, lo_open=True)
        if name == "azimuth_deg":
            return real_scalar(field_name, value, -360.0, 360.0)
        if name == "turbidity":
            return real_scalar(field_name, value, 2.0, 10.0)  # Preetham's fit: T = 2 (very clear) to 10
        if name == "scale":
            return real_scalar(field_name, value, 0.0, MAX_VALUE, lo_open=True)
        if name == "sky":
            return flag(field_name, value)
        raise AssertionError(name)

    # -- dict form ---------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"type": self.type}
        for name in _FIELDS[self.type]:
            v = getattr(self, name)
            out[name] = list(v) if isinstance(v, tuple) else v
        if self.name:
            out["name"] = self.name
        return out

    @classmethod
    def from_dict(cls, d: Any) -> Light:
        if not isinstance(d, dict):
            raise ValueError(f"a light must be a dict with a 'type', got {brief(d)}")
        kind = d.get("type")
        if kind not in LIGHT_TYPES:
            raise ValueError(f"unknown light type {brief(kind)}; known: {', '.join(LIGHT_TYPES)}")
        known = {"type", "name", *_FIELDS[kind]}
        unknown = set(d) - known
        if unknown:
            raise ValueError(f"unknown {kind} light keys: {', '.join(sorted(map(str, unknown)))}; "
                             f"known: {', '.join(sorted(known))}")
        return cls(**d)

    # -- what the renderer gets ----------------------------------------------------------------
    def sun_direction(self) -> np.ndarray:
        """Unit vector from the scene towards the sun (``sun`` lights)."""
        el, az = math.radians(self.elevation_deg), math.radians(self.azimuth_deg)
        return np.array([math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)])


def lights_of(value: Any) -> tuple[Light, ...]:
    """A scene's ``lights`` from a list of Light objects or dicts."""
    if value is None:
        return ()
    if isinstance(value, (dict, str, bytes)) or not hasattr(value, "__iter__"):
        raise ValueError(f"lights must be a list of light dicts, got {brief(value)}")
    out = []
    for i, item in enumerate(value):
        try:
            out.append(item if isinstance(item, Light) else Light.from_dict(item))
        except TypeError as e:
            raise ValueError(f"light {i}: {e}") from None
        except ValueError as e:
            raise ValueError(f"light {i}: {e}") from None
    suns = [lt for lt in out if lt.type == "sun" and lt.sky]
    if len(suns) > 1:
        raise ValueError("at most one sun may bring its sky (set \"sky\": false on the others)")
    return tuple(out)


def add_to_core(core_scene, light: Light) -> None:
    """Add ``light`` to a ``_core.RenderScene`` (a sun as its directional light)."""
    if light.type == "point":
        core_scene.add_point_light(list(light.position), *colour_of(light.intensity))
    elif light.type == "spot":
        rgb, bins = colour_of(light.intensity)
        core_scene.add_spot_light(list(light.position), list(light.direction), rgb, light.cutoff_angle_deg,
                                  light.beam_width_deg, bins)
    elif light.type == "directional":
        rgb, bins = colour_of(light.irradiance)
        core_scene.add_directional_light(list(light.direction), rgb, light.angular_diameter_deg, bins)
    else:
        from bsdflab.render.sky import sun_irradiance, sun_spectrum

        core_scene.add_directional_light((-light.sun_direction()).tolist(), sun_irradiance(light).tolist(),
                                         light.angular_diameter_deg, sun_spectrum(light).tolist())
