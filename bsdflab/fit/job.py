"""Job kind "fit": a fitting study (bsdflab.fit.study, as ``bsdflab fit run``) as a job, so
the HTTP service runs it (``register_kind("fit", "bsdflab.fit.job")``).

Request (normalised)::

    {"config": {...fit.toml as JSON...},
     "data": [{"hash": "<sha256 of an uploaded file>", "name": "R_15deg.ProcSpec"}, ...],
     "sidecar": {...an import sidecar as JSON...} | null}

The data files are uploads (bsdflab.service.fit_uploads) stored as ``<hash>.fitdata`` in the
artefact folder (``out_dir``); ``name`` is the file's name as the readers see it (its suffix
tells the format, and an angle in it places the curve). ``sidecar`` is the import sidecar of a wide
CSV or of instrument spectra (docs/fit_data.md), absent for the long CSV.

A config with ``[structure]`` is a structure + instrument fit (bsdflab.fit.stack_study, as
``bsdflab fit`` runs it): one dataset from ``data``, or ``[[dataset]]`` entries that name their
upload by ``hash`` (never a path: ``data`` there is refused), each read as a long CSV.

Artefacts: the study folder ``<key>.fit/`` (summary.json, material.json, posterior.nc, the
figures, ...), written beside and renamed into place by ``run_study``. Progress runs through
the stages emulator (the full model's), MAP, sampling and the figures and renders; a cancel
is seen within one sampler step, one MAP iteration or one emulator solve.
"""
from __future__ import annotations

import contextlib
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

from bsdflab.fit.config import FitConfig
from bsdflab.fit.data import Dataset
from bsdflab.jobs.keys import job_key, plain_json

FIELDS = {"config", "data", "sidecar"}
SUFFIX = ".fitdata"
MAX_FILES = 256
HASH = re.compile(r"^[0-9a-f]{64}$")
# a plain file name: the readers take the suffix and the angle from it; no folder, no dot first
NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9 ._+()-]{0,127}$")
# the share of the progress bar each stage of a study ends at (stages bsdflab.fit reports)
STAGES = {"emulator": (0.0, 0.15), "MAP": (0.15, 0.25), "sampling": (0.25, 0.85)}
AFTER = (0.85, 1.0)   # figures, appearance and renders (the C++ renders report "rendering")


def stored_path(out_dir: Path, content_hash: str) -> Path:
    return Path(out_dir) / f"{content_hash}{SUFFIX}"


def check_name(where: str, name) -> str:
    if not isinstance(name, str) or not NAME.match(name) or name.endswith("."):
        raise ValueError(f"{where} must be a plain file name (letters, digits, space and ._+()-, at most 128 "
                         f"characters, no folder), got {str(name)[:80]!r}")
    return name


def is_structure(request: dict[str, Any]) -> bool:
    """A structure + instrument fit (a ``[structure]`` table; bsdflab.fit.stack_config)."""
    return isinstance(request.get("config"), dict) and "structure" in request["config"]


def config_of(request: dict[str, Any]):
    """The config of a request (ValueError naming the TOML section and key): a FitConfig, or a
    structure fit's (bsdflab.fit.full_stack_config) with its [[dataset]] uploads named by file."""
    if is_structure(request):
        return structure_config(request)
    return FitConfig.parse(request["config"], "")


def structure_config(request: dict[str, Any], folder: str | None = None):
    """A structure fit's config. Over HTTP a ``[[dataset]]`` names its upload by ``hash`` (one of
    the request's ``data``), never a path (``data`` there is refused); the hash becomes the copy
    of that upload in ``folder`` (None: its name only, for checking: nothing is read)."""
    from bsdflab.fit.full_stack_config import parse_structure_config

    d = dict(request["config"])
    names = {item["hash"]: item["name"] for item in request.get("data") or () if isinstance(item, dict)}
    entries = d.get("dataset")
    if isinstance(entries, list):
        out = []
        for i, e in enumerate(entries):
            where = f"config.dataset[{i}]"
            if not isinstance(e, dict):
                raise ValueError(f"{where} must be a table (name, hash, instrument)")
            if "data" in e:   # a path on the server: never read for a client
                raise ValueError(f"{where}.data: a path is not accepted over HTTP; give hash = <the upload's "
                                 f"hash> (POST /v1/fits/datasets) and list it in data")
            h = e.get("hash")
            if not isinstance(h, str) or not HASH.match(h):
                raise ValueError(f"{where}.hash must be 64 lowercase hex digits (an upload's hash)")
            if h not in names:
                raise ValueError(f"{where}.hash {h} is not one of the request's data ({{\"hash\", \"name\"}})")
            out.append({**{k: v for k, v in e.items() if k != "hash"}, "data": names[h]})
        d["dataset"] = out
    # the config's folder is the uploads' (relative data names resolve there); none is copied in
    source = os.path.join(folder, "config.toml") if folder else ""
    return parse_structure_config(d, source)


def normalise(request: dict[str, Any]) -> dict[str, Any]:
    unknown = set(request) - FIELDS
    if unknown:
        raise ValueError(f"unknown fit request fields: {', '.join(sorted(unknown))}")
    config = request.get("config")
    if not isinstance(config, dict):
        raise ValueError("config must be the fit's TOML as a JSON object ([parameters], [sampler], ...)")
    if not is_structure(request):   # the config first; a structure's needs its data's hashes
        config_of({"config": config})
    data = request.get("data")
    if not isinstance(data, list) or not 1 <= len(data) <= MAX_FILES:
        raise ValueError(f"data must be a list of 1 to {MAX_FILES} uploaded files ({{\"hash\", \"name\"}})")
    files, names = [], set()
    for i, item in enumerate(data):
        if not isinstance(item, dict) or set(item) != {"hash", "name"}:
            raise ValueError(f"data[{i}] must be {{\"hash\": <64 hex digits>, \"name\": <file name>}}")
        if not isinstance(item["hash"], str) or not HASH.match(item["hash"]):
            raise ValueError(f"data[{i}].hash must be 64 lowercase hex digits (an upload's hash)")
        name = check_name(f"data[{i}].name", item["name"])
        if name in names:
            raise ValueError(f"data[{i}].name {name!r} is given twice (the names place the curves)")
        if name == "config.toml" and is_structure(request):   # the study copies that file as its config
            raise ValueError(f"data[{i}].name: 'config.toml' is the study's own config; rename the upload")
        names.add(name)
        files.append({"hash": item["hash"], "name": name})
    if is_structure(request):
        _check_structure(config, files, request.get("sidecar"))
    spec = request.get("sidecar")
    if spec is not None:
        from bsdflab.fit.readers import parse_spec

        if not isinstance(spec, dict):
            raise ValueError("sidecar must be the import sidecar's TOML as a JSON object, or null")
        ref = spec.get("reference")
        if isinstance(ref, dict) and "file" in ref:   # a path on the server: never read for a client
            raise ValueError("sidecar: [reference] file is not accepted over HTTP; give the standard's "
                             "reflectance instead")
        if "name_pattern" in spec:   # a client's regular expression: re holds the GIL while it backtracks
            raise ValueError("sidecar: name_pattern is not accepted over HTTP (a regular expression can backtrack "
                             "for hours in the server); place the curves with [columns] or [files], angles_deg, "
                             "or angles in the names (R_20deg.csv)")
        parse_spec(spec, "sidecar")
    out = {"config": config, "data": files, "sidecar": spec}
    plain_json(out, "fit")
    return out


def _check_structure(config: dict[str, Any], files: list[dict[str, str]], sidecar) -> None:
    """A structure config with its [[dataset]] hashes among the files, each file one dataset's."""
    config_of({"config": config, "data": files})
    if not isinstance(config.get("dataset"), list):
        return
    used = {e.get("hash") for e in config["dataset"] if isinstance(e, dict)}
    for i, item in enumerate(files):
        if item["hash"] not in used:
            raise ValueError(f"data[{i}]: no [[dataset]] names hash {item['hash']} (each file is one "
                             f"dataset's, by its hash)")
    if sidecar is not None:
        raise ValueError("sidecar: a [[dataset]] co-refinement reads each upload as a long CSV (as "
                         "bsdflab fit does); give no sidecar")


def key(request: dict[str, Any]) -> str:
    """SHA-256 of the canonical request, the kind and the package version."""
    return job_key("fit", request)


def folder(request_key: str) -> str:
    return f"{request_key}.fit"


def study_files(request_key: str, out_dir: Path) -> dict[str, str]:
    """{name: path relative to out_dir} of every file the study wrote (the only names served)."""
    base = Path(out_dir) / folder(request_key)
    return {p.name: f"{folder(request_key)}/{p.name}" for p in sorted(base.iterdir()) if p.is_file()}


def load_dataset(request: dict[str, Any], out_dir: Path) -> tuple[Dataset, list[str]]:
    """The dataset the request's files make (bsdflab.fit.readers), read from copies under their
    given names; messages name those names (file, line, column), never a server folder.
    ValueError for a missing upload or a file that does not read."""
    from bsdflab.fit.readers import ImportSpec, import_files, parse_spec

    for i, item in enumerate(request["data"]):
        if not stored_path(out_dir, item["hash"]).is_file():
            raise LookupError(f"data[{i}].hash: no uploaded fit data file {item['hash']} (POST /v1/fits/datasets)")
    spec = ImportSpec(source="sidecar") if request["sidecar"] is None else parse_spec(request["sidecar"], "sidecar")
    tmp = tempfile.mkdtemp(dir=out_dir, prefix=".fitdata-")
    try:
        paths = []
        for item in request["data"]:
            path = os.path.join(tmp, item["name"])
            shutil.copyfile(stored_path(out_dir, item["hash"]), path)
            paths.append(path)
        try:
            return import_files(paths, spec)
        except ValueError as e:
            raise ValueError(str(e).replace(tmp + os.sep, "").replace(tmp, "")) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def co_refined(request: dict[str, Any]) -> bool:
    """A structure fit whose [[dataset]] entries name their uploads (each read as a long CSV)."""
    return is_structure(request) and "dataset" in request["config"]


@contextlib.contextmanager
def structure_inputs(request: dict[str, Any], out_dir: Path):
    """(config, data) of a structure fit: data the one Dataset of the request's files (as a
    snake fit's), or None with each [[dataset]] naming a copy of its upload in a folder that
    lives as long as the block; messages name the given names, never a server folder."""
    if not co_refined(request):
        yield structure_config(request), load_dataset(request, out_dir)[0]
        return
    for i, item in enumerate(request["data"]):
        if not stored_path(out_dir, item["hash"]).is_file():
            raise LookupError(f"data[{i}].hash: no uploaded fit data file {item['hash']} (POST /v1/fits/datasets)")
    tmp = tempfile.mkdtemp(dir=out_dir, prefix=".fitdata-")
    try:
        for item in request["data"]:
            shutil.copyfile(stored_path(out_dir, item["hash"]), os.path.join(tmp, item["name"]))
        try:
            yield structure_config(request, tmp), None
        except ValueError as e:
            raise ValueError(str(e).replace(tmp + os.sep, "").replace(tmp, "")) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def check_inputs(request: dict[str, Any], out_dir: Path) -> None:
    """Read the request's data as its job will (ValueError naming the file, line and column;
    LookupError for a missing upload)."""
    if not co_refined(request):
        load_dataset(request, out_dir)
        return
    from bsdflab.fit.stack_study import load_datasets

    with structure_inputs(request, out_dir) as (config, data):
        load_datasets(config, data)


def existing(request: dict[str, Any], out_dir: Path) -> dict[str, Any] | None:
    k = key(request)
    summary = Path(out_dir) / folder(k) / "summary.json"
    if not summary.is_file():   # the folder is renamed into place whole: summary.json means done
        return None
    try:
        return _result(k, Path(out_dir), from_cache=True)
    except (OSError, ValueError):   # an unreadable study is rebuilt, not served
        return None


def _result(k: str, out_dir: Path, from_cache: bool) -> dict[str, Any]:
    import json

    summary = json.loads((out_dir / folder(k) / "summary.json").read_text(encoding="utf-8"))
    brief = {name: summary.get(name) for name in ("rows", "free", "sampler", "converged", "stop_reason",
                                                   "posterior_mean", "map", "seconds", "warnings",
                                                   "predictive_checks")}
    if summary.get("model") == "structure":   # a structure fit's: its datasets, parameter table, emulator
        brief.update({name: summary.get(name) for name in ("model", "datasets", "steps", "parameters", "emulator")})
    return {"hash": k, "files": study_files(k, out_dir), "from_cache": from_cache, "summary": brief}


def run(request: dict[str, Any], out_dir: Path, progress, cancelled, runner=None) -> dict[str, Any]:
    from bsdflab.fit.study import run_study
    from bsdflab.util.progress import monitored

    out_dir = Path(out_dir)
    found = existing(request, out_dir)
    if found is not None:
        return found
    k = key(request)
    reached = [0.0]

    def staged(stage: str, fraction: float) -> None:
        lo, hi = STAGES.get(stage, AFTER)
        # the bar never goes back (a render after the sampler reports its own 0..1)
        reached[0] = max(reached[0], lo + (hi - lo) * fraction)
        progress(reached[0])

    if is_structure(request):
        from bsdflab.fit.stack_study import run_stack_study

        with structure_inputs(request, out_dir) as (config, data), monitored(staged, cancelled):
            run_stack_study(config, out_dir / folder(k), data, progress=False, overwrite=True)
        return _result(k, out_dir, from_cache=False)
    config = config_of(request)
    dataset, _ = load_dataset(request, out_dir)
    with monitored(staged, cancelled):
        run_study(dataset, config, out_dir / folder(k), progress=False, overwrite=True)
    return _result(k, out_dir, from_cache=False)
