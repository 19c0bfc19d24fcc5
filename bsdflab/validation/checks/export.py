"""Export (bsdflab.export, ``bsdflab export``): per format, the Delta E00 that the export's
report states is recomputed from the parameters its file holds, against bsdflab's exact film
colour by an independent path (bsdflab.optics.film_reflectance -> spectrum_to_rgb ->
CIEDE2000); the message states the fitted and the unfitted (the material's own parameters
in the target's model) Delta E00. The model under test is ``{"export": export}``: a report
that understates its colour error must fail."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

from bsdflab.validation.registry import REGISTRY, Outcome, SkipCheck, effort

FORMATS = {"openpbr": (".mtlx", ()), "gltf": (".gltf", ()), "usd": (".usda", ("pxr",)), "blender": (".blend", ())}
LIMIT = 1e-4  # the report rounds its map to 1e-4 (5e-5 at most); the two film-colour paths agree far below


def _exporter():
    from bsdflab.export import export

    return {"export": export}


def exact_film_rgb(ext_ior, film_ior, int_ior, thickness_nm, angles_deg, scales):
    """(A, S, 3) linear sRGB of a single film by the transfer-matrix reflectance (not the
    export's own path)."""
    from bsdflab.optics import FilmLayer, FilmStack, film_reflectance
    from bsdflab.reference.approximations.study import SPECTRAL_GRID_NM
    from bsdflab.spectra import spectrum_to_rgb

    cos = np.cos(np.radians(angles_deg))[:, None]
    cols = []
    for k in scales:
        R = film_reflectance(
            FilmStack(ext_ior, [FilmLayer(film_ior, thickness_nm * k)], int_ior), SPECTRAL_GRID_NM, cos_theta=cos
        )
        cols.append(spectrum_to_rgb(np.asarray(R), SPECTRAL_GRID_NM))
    return np.stack(cols, axis=1)


def delta_e00(rgb, ref):
    import colour

    from bsdflab.reference.approximations.study import rgb_to_lab

    return colour.delta_E(rgb_to_lab(rgb), rgb_to_lab(ref), method="CIE 2000")


def _summary(e) -> str:
    return f"median {np.median(e):.2f}, max {np.max(e):.2f}, >2 on {100 * np.mean(e > 2):.0f} %"


for _fmt, (_suffix, _requires) in FORMATS.items():

    @REGISTRY.check(
        name=f"export/delta-e00/{_fmt}",
        family="export",
        title=f"The {_fmt} export's stated Delta E00 is the colour error of its file",
        model=f"bsdflab export --preset xenopeltis --format {_fmt} (fitted single film)",
        reference="bsdflab's exact film colour (transfer matrix, CIE 1931, linear sRGB) against the "
        "target model at the file's parameters, CIEDE2000 over 17 angles x 7 thickness scales",
        statistic="max |report Delta E00 - recomputed Delta E00| over the map",
        tolerance=f"{LIMIT:g}: deterministic; the report rounds its map to 1e-4 (an error of 5e-5 at "
        "most) and the two film paths (thin-film closed form, transfer matrix) agree far below",
        effort=effort({}, {}),
        make_model=_exporter,
        seed=91,
        requires=_requires,
    )
    def _export(ctx, _fmt=_fmt, _suffix=_suffix):
        from bsdflab.export.fit import TARGET_OUTER_IOR, target_rgb
        from bsdflab.export.material import export_material
        from bsdflab.export.targets import target
        from bsdflab.presets import preset

        if _fmt == "blender":
            from bsdflab.export.blender import blender_python

            try:
                blender_python()  # bpy runs in a child process (.venv-blender): absent, nothing to check
            except ValueError as e:
                raise SkipCheck(str(e)) from None
        model = preset("xenopeltis")
        with tempfile.TemporaryDirectory() as tmp:
            out = str(Path(tmp) / f"snake{_suffix}")
            ctx.model["export"](model, _fmt, out, name="xenopeltis")
            report = json.loads(Path(out + ".report.json").read_text())
        e = report["delta_e00"]
        angles, scales, stated = np.array(e["angles_deg"]), np.array(e["thickness_scales"]), np.array(e["map"])
        m, t, p = export_material(model), target(_fmt), report["parameters"]
        exact = exact_film_rgb(m.ext_ior, m.film_ior, m.int_ior, m.film_thickness_nm, angles, scales)
        fitted = delta_e00(
            target_rgb(
                t, p["film_thickness_nm"]["value"], p["film_ior"]["value"], p["base_ior"]["value"], angles, scales
            ),
            exact,
        )
        # unfitted: the material's own film in the target's model (seen from n = 1, as the targets are)
        unfitted = delta_e00(
            target_rgb(
                t, m.film_thickness_nm, m.film_ior * TARGET_OUTER_IOR / m.ext_ior, m.int_ior / m.ext_ior, angles, scales
            ),
            exact,
        )
        worst = float(np.max(np.abs(stated - fitted)))
        return Outcome(
            worst <= LIMIT,
            worst,
            LIMIT,
            "<=",
            f"fitted Delta E00 {_summary(fitted)} (report: median {e['median']:.2f}, max {e['max']:.2f}); "
            f"unfitted {_summary(unfitted)}; largest report-vs-recomputed difference {worst:.1e}",
            {
                "fitted": {"median": float(np.median(fitted)), "max": float(np.max(fitted))},
                "unfitted": {"median": float(np.median(unfitted)), "max": float(np.max(unfitted))},
                "report": {"median": e["median"], "max": e["max"]},
                "parameters": {k: v["value"] for k, v in p.items()},
            },
        )
