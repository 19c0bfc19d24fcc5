"""``export(model, fmt, out)``: fit, write the target's files and the report, all or nothing.

Every file of an export (the target's file(s), the Blender script, ``<out>.report.json``
and ``<out>.report.png``) is written to a temporary first and published together
(``bsdflab.util.files.write_together``): a failure anywhere (a fit out of range, an invalid
MaterialX document, bpy failing) leaves no file behind.
"""
from __future__ import annotations

import os
from dataclasses import replace

from bsdflab.export.body import fit_material_body
from bsdflab.export.fit import fit
from bsdflab.export.material import export_material
from bsdflab.export.report import export_params, report_dict, write_report_json, write_report_png
from bsdflab.export.targets import target
from bsdflab.util.files import write_together


def check_out(path: str, suffixes: tuple[str, ...]) -> str:
    """The output path, absolute; ValueError for a wrong suffix or a folder we cannot write."""
    if not isinstance(path, (str, os.PathLike)) or not os.fspath(path):
        raise ValueError("out must be a file path")
    p = os.path.abspath(os.fspath(path))
    if not p.lower().endswith(suffixes):
        raise ValueError(f"out {path} must end in {' or '.join(suffixes)} for this format")
    if os.path.isdir(p):
        raise ValueError(f"out {path} is a folder, not a file")
    folder = os.path.dirname(p)
    if not os.path.isdir(folder):
        raise ValueError(f"out {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"out {path}: cannot write in {folder} (permission denied)")
    return p


def _target_files(fmt: str, params: dict, out: str, name: str) -> list[tuple[str, object, str]]:
    if fmt == "openpbr":
        from bsdflab.export.openpbr import validate_mtlx, write_openpbr

        def write(tmp):
            write_openpbr(params, tmp)
            ok, message = validate_mtlx(tmp)
            if not ok:
                raise RuntimeError(f"MaterialX validate() failed: {message}")
        return [(out, write, ".mtlx")]
    if fmt == "usd":
        from bsdflab.export.usd import write_usd

        return [(out, lambda tmp: write_usd(params, tmp), ".usda")]
    if fmt == "gltf":
        from bsdflab.export.gltf import gltf_writers

        return gltf_writers(params, out)
    from bsdflab.export.blender import blender_script, write_blend

    def write_script(tmp):
        with open(tmp, "w") as fh:
            fh.write(blender_script(params, name, save_as=os.path.basename(out)))
    return [(out, lambda tmp: write_blend(params, tmp, name), ".blend"), (out + ".py", write_script, ".py")]


def export(model, fmt: str, out: str, name: str = "bsdflab", substitute: bool = False) -> dict:
    """Export a BSDF (object or dict) to ``fmt`` (``bsdflab.export.FORMATS``) at ``out``;
    returns the report dict (also written to ``<out>.report.json``). ``substitute``: export
    a multilayer film as the single film that looks most like it (else ValueError)."""
    t = target(fmt)
    out = check_out(out, t.suffixes)
    m = export_material(model, substitute)
    f = fit(m, t)
    body = fit_material_body(model, t, f)
    if body is not None:
        m = replace(m, body_rgb=tuple(float(x) for x in body.rgb))
    params = export_params(m, f)
    files = _target_files(fmt, params, out, name)
    report = report_dict(fmt, t, m, f, params, [os.path.basename(p) for p, _, _ in files], body)
    files += [(out + ".report.json", lambda tmp: write_report_json(report, tmp), ".json"),
              (out + ".report.png", lambda tmp: write_report_png(report, f, tmp), ".png")]
    write_together(files)
    return report
