"""The export report: fitted parameters with their ranges, the Delta E00 map and what was dropped.

``<out>.report.json`` (this dict) and ``<out>.report.png`` (the map, and the exact and
exported specular colours over angle at the nominal thickness) accompany every export.
"""
from __future__ import annotations

import json

import numpy as np

from bsdflab.export.body import BodyFit
from bsdflab.export.fit import FitResult
from bsdflab.export.material import SPREAD, ExportMaterial
from bsdflab.export.targets import Target

MATCHED = ["specular colour vs incidence angle (thin-film Fresnel, 0-80 deg) over the film-thickness spread: fitted "
           "by CIEDE2000", "diffuse body colour: fitted by CIEDE2000 so that base_color (1 - F(theta)) matches the "
           "layered model's scattered hemispherical albedo (everything but the top interface's reflection) at 0, 30, "
           "50, 70 deg, per channel", "roughness: sqrt(GGX alpha), copied"]
NOT_REPRESENTED = ["the pigment slab's spectral absorption and its angular darkening (folded into one RGB base colour)",
                   "the scale texture (per-scale thickness variation): one thickness; the map shows the spread",
                   "multilayer film stacks (one film only)", "the PFMC layered interreflections between film and body"]


def export_params(m: ExportMaterial, f: FitResult) -> dict:
    return {"base_color": [round(float(x), 6) for x in m.body_rgb], "roughness": round(float(np.sqrt(m.alpha)), 6),
            "base_ior": f.base_ior, "film_ior": f.film_ior, "film_thickness_nm": f.thickness_nm}


def report_dict(fmt: str, target: Target, m: ExportMaterial, f: FitResult, params: dict, files: list[str],
                body: BodyFit | None = None) -> dict:
    ranges = {"base_ior": (target.base_ior, "", "specular index of the base (relative to n = 1 outside)"),
              "film_ior": (target.film_ior, "", "thin-film index"),
              "film_thickness_nm": (target.thickness_nm, "nm", "thin-film thickness"),
              "roughness": ((0.0, 1.0), "", "sqrt(GGX alpha)"),
              "base_color": ((0.0, 1.0), "linear sRGB", "diffuse body colour")}
    return {
        "format": fmt, "target": target.name, "target_model": target.model_name, "files": files,
        "parameters": {k: {"value": params[k], "range": list(ranges[k][0]), "unit": ranges[k][1],
                           "meaning": ranges[k][2]} for k in ranges},
        "material": m.to_dict(),
        "delta_e00": {**f.summary(), "angles_deg": f.angles_deg.tolist(), "thickness_scales": f.scales.tolist(),
                      "thickness_spread": SPREAD, "map": np.round(f.delta_e, 4).tolist()},
        "body_delta_e00": body.summary() if body is not None else None,
        "matched": MATCHED, "not_represented": NOT_REPRESENTED, "dropped": list(m.dropped),
    }


def write_report_json(report: dict, path: str) -> None:
    with open(path, "w") as fh:
        json.dump(report, fh, indent=1)


def write_report_png(report: dict, f: FitResult, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    e = f.delta_e
    im = ax[0].imshow(e, origin="lower", aspect="auto", cmap="magma", vmin=0, vmax=max(4.0, float(e.max())),
                      extent=[f.scales[0], f.scales[-1], f.angles_deg[0], f.angles_deg[-1]])
    ax[0].contour(f.scales, f.angles_deg, e, levels=[1.0, 2.0], colors=["w", "c"], linewidths=0.8)
    fig.colorbar(im, ax=ax[0], label="Delta E00 (contours 1, 2)")
    ax[0].set(xlabel="film thickness / nominal", ylabel="incidence angle (deg)",
              title=f"{report['format']}: median {report['delta_e00']['median']:.2f}, "
                    f">2 on {100 * report['delta_e00']['share_above_2']:.0f} %")
    mid = len(f.scales) // 2
    strip = np.stack([f.exact_rgb[:, mid], f.target_rgb[:, mid]])
    scale = max(float(strip.max()), 1e-6)
    ax[1].imshow((np.clip(strip / scale, 0, 1)) ** (1 / 2.2), aspect="auto",
                 extent=[f.angles_deg[0], f.angles_deg[-1], 1.5, -0.5])
    ax[1].set_yticks([0, 1], ["exact", report["format"]])
    ax[1].set(xlabel="incidence angle (deg)", title="specular colour, nominal thickness (scaled)")
    fig.savefig(path, dpi=90, format="png")
    plt.close(fig)
