"""The service's contract: a small, derandomised schemathesis sample against a real
``bsdflab serve`` (a subprocess on 127.0.0.1 and a free port; bsdflab.service sits above
bsdflab.validation in the layers, so the check is the service's client, not its importer).
Every schemathesis check but ``positive_data_acceptance`` (physical ranges are the Python
API's to refuse with a 422) must hold, with zero 5xx, and the computing operations must
answer some cases (an API that refuses everything would pass the rest). The model under test
is ``{"serve": callable(folder, limits) -> (url, stop)}``: a server that answers 500 must fail.
The quick level's server caps a lobe's resolution (BSDFLAB_LIMIT_LOBE_RESOLUTION): the
contract is the same, and the lobe operations' examples at the default 181 took 30 of its
68 s; standard and full run the default limits."""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bsdflab.validation.registry import REGISTRY, Outcome, effort

COMPUTING = ("POST /v1/bsdf/eval", "POST /v1/thinfilm/spectrum")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def serve(folder: Path, limits: dict[str, str] | None = None, timeout: float = 120.0):
    """Start ``bsdflab serve`` with its data in ``folder`` and the settings ``limits``
    (BSDFLAB_LIMIT_* variables) over the environment's: (url, stop)."""
    import urllib.error
    import urllib.request

    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    log = open(folder / "server.log", "w")  # noqa: SIM115 -- closed by stop()
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bsdflab.cli.main",
            "serve",
            "--host",  # never the environment's (the container image sets BSDFLAB_HOST=0.0.0.0)
            "127.0.0.1",
            "--port",
            str(port),
            "--data-dir",
            str(folder / "data"),
            "--workers",
            "1",
            "--log-level",
            "warning",
        ],
        stdout=log,
        stderr=subprocess.STDOUT,
        env={**os.environ, **(limits or {})},
    )

    def stop():
        if process.poll() is None:
            process.terminate()
            try:
                process.wait(30)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(30)
        log.close()

    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if process.poll() is not None:
            stop()
            raise RuntimeError(
                f"bsdflab serve exited with {process.returncode}: {(folder / 'server.log').read_text()[-2000:]}"
            )
        try:
            with urllib.request.urlopen(f"{url}/healthz", timeout=2) as response:
                if response.status == 200:
                    return url, stop
        except (urllib.error.URLError, OSError):
            pass
        time.sleep(0.1)
    stop()
    raise RuntimeError("bsdflab serve did not answer /healthz in time")


def _finite_2xx(response) -> bool:
    if not 200 <= response.status_code < 300:
        return False
    if "json" not in response.headers.get("content-type", ""):
        return True
    bad = []

    def walk(x):
        if isinstance(x, dict):
            for v in x.values():
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)
        elif isinstance(x, float) and not math.isfinite(x):
            bad.append(x)

    walk(json.loads(response.content))
    return not bad


def _cancel_job(url: str, response) -> None:
    """DELETE the job a 202 started: the sample never awaits it, and it would compute until
    the server stops (an empty POST /v1/validations is the whole quick report)."""
    import urllib.error
    import urllib.request

    try:
        job = json.loads(response.content)["id"]
    except (ValueError, KeyError, TypeError):
        return  # no job named: nothing to cancel (the response checks judge the body)
    request = urllib.request.Request(f"{url}/v1/jobs/{job}", method="DELETE")
    try:
        urllib.request.urlopen(request, timeout=30).close()
    except (urllib.error.URLError, OSError):
        pass  # finished already, or gone: nothing left to stop


def fuzz(url: str, examples: int) -> dict:
    """Counts (cases, finite 2xx, 5xx), 2xx per operation and the failures, over every operation;
    every job a case starts is cancelled once its answer is checked."""
    import schemathesis
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st
    from schemathesis.generation import GenerationMode
    from schemathesis.specs.openapi.checks import positive_data_acceptance

    schema = schemathesis.openapi.from_url(f"{url}/openapi.json")
    counts = {"cases": 0, "ok": 0, "5xx": 0}
    ok_by_operation: dict[str, int] = {}
    failures: list[str] = []

    def sample(operation, strategy, n) -> None:
        @given(case=strategy)
        @settings(
            max_examples=n, deadline=None, database=None, derandomize=True, suppress_health_check=list(HealthCheck)
        )
        def check(case):
            counts["cases"] += 1
            response = case.call(timeout=120)
            ok = _finite_2xx(response)
            counts["ok"] += ok
            ok_by_operation[operation.label] = ok_by_operation.get(operation.label, 0) + ok
            counts["5xx"] += response.status_code >= 500
            try:
                case.validate_response(response, excluded_checks=[positive_data_acceptance])
            except BaseException as e:  # noqa: BLE001 -- an exception group; collected, reported together
                failures.append(f"{operation.label}: {str(e)[:600]}")
                raise
            finally:
                if response.status_code == 202:
                    _cancel_job(url, response)

        before = len(failures)
        try:
            check()
        except (KeyboardInterrupt, SystemExit):
            raise
        except BaseException as e:  # noqa: BLE001 -- schemathesis raises exception groups; recorded above
            if len(failures) == before:  # not a response check: the sample itself could not run
                failures.append(f"{operation.label}: {type(e).__name__}: {str(e)[:600]}")

    def fuzz_operation(operation) -> None:
        examples_of_schema = operation.get_strategies_from_examples()
        if examples_of_schema:  # the schema's own complete example first: a case that must succeed
            sample(operation, st.one_of(*examples_of_schema), 1)
        sample(
            operation,
            st.one_of(
                operation.as_strategy(GenerationMode.POSITIVE),
                operation.as_strategy(GenerationMode.NEGATIVE),
                *examples_of_schema,
            ),
            examples,
        )

    for result in schema.get_all_operations():
        fuzz_operation(result.ok())
    return {**counts, "ok_by_operation": ok_by_operation, "failures": failures}


@REGISTRY.check(
    name="service/schemathesis-sample",
    family="service",
    title="The HTTP API keeps its OpenAPI contract (a schemathesis sample)",
    model="bsdflab serve (a real process, 1 worker, a fresh data folder)",
    reference="the service's own /openapi.json: schemathesis' response checks (status codes, "
    "content types, schema conformance, no 5xx) on derandomised valid, invalid and "
    "example cases per operation",
    statistic="failed cases + 5xx responses + computing operations that never answered",
    tolerance="0: deterministic cases (derandomised hypothesis); a contract holds or it does not. "
    "tests/service/test_schema_fuzz_live.py runs the large sample and the stateful run",
    effort=effort({"examples": 2, "limits": {"BSDFLAB_LIMIT_LOBE_RESOLUTION": "48"}}, {"examples": 12},
                  {"examples": 120}),
    make_model=lambda: {"serve": serve},
    seed=0,
    requires=("schemathesis",),
)
def _schemathesis(ctx):
    with tempfile.TemporaryDirectory() as tmp:
        url, stop = ctx.model["serve"](Path(tmp), ctx.effort.get("limits"))
        try:
            result = fuzz(url, int(ctx.effort["examples"]))
        finally:
            stop()
    silent = [op for op in COMPUTING if result["ok_by_operation"].get(op, 0) == 0]
    bad = len(result["failures"]) + result["5xx"] + len(silent)
    return Outcome(
        bad == 0,
        bad,
        0,
        "<=",
        f"{result['cases']} cases, {result['ok']} 2xx with finite numbers, {result['5xx']} 5xx, "
        f"{len(result['failures'])} failed operations" + (f"; never answered: {', '.join(silent)}" if silent else ""),
        {
            "cases": result["cases"],
            "ok": result["ok"],
            "5xx": result["5xx"],
            "failures": result["failures"][:20],
            "silent": silent,
        },
    )
