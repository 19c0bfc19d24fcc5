"""The check families added for issue 32 item 7 (solvers, coverage, fit, measured, export,
service): each is registered (that each passes on the real code is
test_validation_registry.py's, on the quick report), and each has power: a deliberate mutation injected through
``Check.with_model`` (the thing under test, broken in one place) turns its row red.

Mutations (each run once here, figures in the closing report):
* solvers: the solver given the stack with its slabs' scattering dropped (sigma_s = 0);
* coverage: a tabulate whose stated cell errors are half the true ones; per pair,
  ``Layered.estimate`` with error_walks=0 (the value's own spread) on the snake, at level
  standard (960 pairs: quick's 96 hold too few |z| > 3 to tell it from the normal);
* fit: posteriors 0.3x too narrow about their mean (an over-confident sampler);
* measured: a reader 1 % high in eval;
* export: a report whose Delta E00 map is half the file's colour error;
* service: a server that keeps the real OpenAPI document and answers 500 to every operation.
"""

from __future__ import annotations

import json
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import numpy as np
import pytest

from bsdflab.validation import REGISTRY, load_checks
from bsdflab.validation.runner import run_check
from support.liveness import HANG_S

load_checks()
NEW = ("solvers", "coverage", "fit", "measured", "export", "service")


def _run(check, make_model):
    return run_check(check.with_model(make_model, name=f"{check.name}/mutated"), "quick")


@pytest.mark.parametrize("family", NEW)
def test_family_is_registered(family):
    """Each family has checks registered under its name. That each
    passes there is test_validation_registry.py::test_registered_check_passes_at_quick, on
    the session's one quick report (tests/validation/conftest.py): reading the same rows here
    made this file need that report too, and pytest-xdist then ran it on both workers.
    Mutation checked: a family's checks unregistered (its module not loaded) fails it."""
    checks = REGISTRY.select(families=[family])
    assert checks, family
    assert all(c.family == family for c in checks)


def _no_scattering_solve(stack, wavelengths):
    import bsdflab as bl
    from bsdflab.solvers import solve

    d = stack.to_dict()
    for slab in d["slabs"]:
        slab["sigma_s"] = 0.0
    return solve(bl.from_dict(d), wavelengths)


@pytest.mark.parametrize(
    "name", ["solvers/adding-doubling-vs-pfmc/xenopeltis", "solvers/adding-doubling-vs-oracle/smooth-coat"]
)
def test_solvers_fail_a_solver_that_drops_scattering(name):
    check = REGISTRY[name]
    stack = check.make_model()["stack"]
    r = _run(check, lambda: {"stack": stack, "solve": _no_scattering_solve})
    assert r.status == "fail", r.message
    print(f"{name} mutated: {r.message}")


def test_coverage_fails_tables_that_understate_their_errors():
    from dataclasses import replace

    from bsdflab.tables import tabulate

    def understated(*args, **kwargs):
        t = tabulate(*args, **kwargs)
        return replace(t, stderr=t.stderr * 0.5)

    check = REGISTRY["coverage/table-cells/plastic"]
    r = _run(check, lambda: {"stack": check.make_model()["stack"], "tabulate": understated})
    assert r.status == "fail", r.message
    print(f"coverage mutated: {r.message}")


def test_coverage_fails_pair_errors_from_their_own_walks():
    def own_walks(stack, wi, wo, seed):
        return stack.estimate(wi, wo, [450.0, 550.0, 650.0], samples=256, seed=seed, scattered_only=True, error_walks=0)

    check = REGISTRY["coverage/eval-with-error-pairs/xenopeltis"]
    stack = check.make_model()["stack"]
    mutated = check.with_model(lambda: {"stack": stack, "estimate": own_walks}, name=f"{check.name}/mutated")
    r = run_check(mutated, "standard")
    assert r.status == "fail", r.message
    print(f"pair coverage mutated: {r.message}")


def test_fit_fails_an_overconfident_posterior():
    check = REGISTRY["fit/recovery/thin-film"]
    honest = check.make_model()["fit"]

    def narrow(data, config):
        draws = honest(data, config)
        return draws.mean(axis=0) + 0.3 * (draws - draws.mean(axis=0))

    r = _run(check, lambda: {"fit": narrow})
    assert r.status == "fail", r.message
    print(f"fit mutated: {r.message}")


def test_measured_fails_a_reader_one_percent_high():
    from bsdflab.measured import Measured

    class High(Measured):
        def eval(self, wi, wo, *args, **kwargs):
            return 1.01 * np.asarray(super().eval(wi, wo, *args, **kwargs))

    r = _run(REGISTRY["measured/rgl-vs-mitsuba/gold"], lambda: {"reader": High})
    assert r.status == "fail", r.message
    print(f"measured mutated: {r.message}")


def test_export_fails_a_report_that_understates_delta_e():
    from bsdflab.export import export

    def flattering(model, fmt, out, **kwargs):
        report = export(model, fmt, out, **kwargs)
        path = Path(out + ".report.json")
        doc = json.loads(path.read_text())
        doc["delta_e00"]["map"] = (0.5 * np.array(doc["delta_e00"]["map"])).tolist()
        path.write_text(json.dumps(doc))
        return report

    r = _run(REGISTRY["export/delta-e00/gltf"], lambda: {"export": flattering})
    assert r.status == "fail", r.message
    print(f"export mutated: {r.message}")


def test_service_fails_a_server_that_answers_500(tmp_path):
    from bsdflab.validation.checks.service import serve

    url, stop = serve(tmp_path)
    try:
        import urllib.request

        with urllib.request.urlopen(f"{url}/openapi.json", timeout=HANG_S) as response:
            schema = response.read()
    finally:
        stop()

    class Broken(BaseHTTPRequestHandler):
        def _answer(self):
            length = int(self.headers.get("content-length") or 0)
            if length:
                self.rfile.read(length)
            ok = self.path.split("?")[0] in ("/openapi.json", "/healthz")
            body = schema if self.path.startswith("/openapi.json") else b'{"status": "ok"}' if ok else b"{}"
            self.send_response(200 if ok else 500)
            self.send_header("content-type", "application/json")
            self.send_header("content-length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        do_GET = do_POST = do_PUT = do_DELETE = do_PATCH = _answer

        def log_message(self, *args):
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Broken)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()

    def broken_serve(folder, limits):
        return f"http://127.0.0.1:{server.server_address[1]}", lambda: None

    try:
        r = _run(REGISTRY["service/schemathesis-sample"], lambda: {"serve": broken_serve})
    finally:
        server.shutdown()
        thread.join()
    assert r.status == "fail" and r.details["5xx"] > 0, r.message
    print(f"service mutated: {r.message}")


def test_cli_lists_families_and_selects_by_family(tmp_path):
    import subprocess
    import sys

    from bsdflab.validation import FAMILIES

    cmd = [sys.executable, "-m", "bsdflab.cli.main", "validate"]
    listed = subprocess.run([*cmd, "--list"], capture_output=True, text=True, timeout=120)
    assert listed.returncode == 0, listed.stderr
    first = listed.stdout.splitlines()[0]
    assert first.startswith("families: ") and all(f"{f} (" in first for f in FAMILIES), first
    only = subprocess.run(
        [*cmd, "--list", "--family", "solvers", "--family", "fit"], capture_output=True, text=True, timeout=120
    )
    names = [line.split()[0] for line in only.stdout.splitlines()[1:]]
    assert names and all(n.startswith(("solvers/", "fit/")) for n in names), only.stdout
    bad = subprocess.run([*cmd, "--list", "--family", "nope"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "valid: basic" in bad.stderr, bad.stderr


def test_job_request_families_are_normalised():
    from bsdflab.validation.job import normalise

    r = normalise({"level": "quick", "families": ["fit", "solvers", "fit"]})
    assert r["families"] == ["solvers", "fit"]  # registry order, once each
    with pytest.raises(ValueError, match="valid: basic, rough"):
        normalise({"families": ["nope"]})
    with pytest.raises(ValueError, match="non-empty list"):
        normalise({"families": "fit"})


def test_results_schema_names_every_family():
    from bsdflab.validation import FAMILIES, SCHEMA_PATH

    schema = json.loads(SCHEMA_PATH.read_text())
    assert schema["$defs"]["check"]["properties"]["family"]["enum"] == list(FAMILIES)


def test_cycles_check_statistic_rejects_the_materialx_model():
    """The Cycles check's statistic on stand-in "renders" made by the Cycles model itself
    (with a 1e-4 seed-to-seed scatter): the Cycles model passes, MaterialX's Belcour-Barla
    model fails. Real Cycles renders enter where a Blender interpreter exists (the check in
    the quick report; tests/export/test_cycles_thin_film.py)."""
    from bsdflab.reference.approximations import belcour_barla_rgb
    from bsdflab.reference.approximations.cycles import cycles_thin_film_rgb
    from bsdflab.validation.checks.cycles import pixel_cosines

    def stand_in(params, thicknesses, folder, size=48, spp=4, seeds=(0, 1)):
        cos = np.nan_to_num(pixel_cosines(size), nan=1.0)
        img = np.stack([cycles_thin_film_rgb(1.0, params["film_ior"], params["base_ior"], d, cos) for d in thicknesses])
        return np.stack([img + 1e-4 * np.random.default_rng(s).standard_normal(img.shape) for s in seeds])

    check = REGISTRY["export/cycles-model-vs-cycles"]
    good = _run(check, lambda: {"model": cycles_thin_film_rgb, "render": stand_in})
    bad = _run(check, lambda: {"model": belcour_barla_rgb, "render": stand_in})
    assert good.status == "pass", good.message
    assert bad.status == "fail", bad.message
    print(f"cycles stand-in: {good.message}; Belcour-Barla: {bad.message}")
