"""Fit data files uploaded over HTTP (``POST /v1/fits/datasets``), stored by content hash.

A file is read under the name the client gives (its suffix and contents tell the format,
bsdflab.fit.readers) before it enters the store as ``<sha256>.fitdata``: the fit's long CSV
and instrument spectra (Ocean Optics .ProcSpec, OceanView and Avantes text, JCAMP-DX, ...)
are read whole; a wide CSV only as text, since its delimiter, decimal mark and wavelength
column may come from the sidecar that the fit request carries (it is read whole then).
A reader's complaint names the file by the client's name, its line and column, never a
server folder. Files are read in a check worker process (bsdflab.service.offload), never
in the web process. A .ProcSpec is a zip: its members may inflate to at most 4 MiB (its reader,
bsdflab.fit.readers.oceanoptics_procspec, whatever the name). Uploads count against the same
per-key quotas as measured files (bsdflab.service.uploads).
"""
from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
import zipfile
from pathlib import Path
from typing import Any

from fastapi import HTTPException

from bsdflab.fit.job import SUFFIX, check_name
from bsdflab.fit.readers.oceanoptics_procspec import check_sizes
from bsdflab.service import uploads
from bsdflab.service.upload_gate import quota_message
from bsdflab.util.files import write_atomically

KIND = "fitdata"
TEXT_ONLY = ("wide",)        # formats whose reading needs the fit request's sidecar


def check_zip(path: str, name: str) -> None:
    """A zip's declared sizes (the ProcSpec reader checks them again whatever the name)."""
    try:
        with zipfile.ZipFile(path) as z:
            infos = z.infolist()
    except (zipfile.BadZipFile, OSError, EOFError) as e:
        raise ValueError(f"{name}: not a readable zip archive ({type(e).__name__})") from None
    check_sizes(infos, name)


def read_check(path: str, name: str) -> dict[str, Any]:
    """Read the file at ``path`` (named ``name``) as the fit would; its summary. ValueError
    with the reader's message otherwise."""
    from bsdflab.fit.readers import ImportSpec, reader_for

    if name.lower().endswith(".procspec"):
        check_zip(path, name)
    reader = reader_for(path)
    spec = ImportSpec(source="the upload")
    if reader.long:
        dataset = reader.read_dataset(path, spec)
        return {"format": reader.name, "rows": len(dataset)}
    if reader.name in TEXT_ONLY:
        with open(path, encoding="utf-8", errors="strict") as f:
            lines = sum(1 for _ in f)
        return {"format": reader.name, "lines": lines}
    spectra = reader.read(path, spec)
    return {"format": reader.name, "curves": len(spectra), "points": int(sum(len(s.value) for s in spectra))}


def read_summary(path: str, name: str, folder: str) -> dict[str, Any]:
    """``read_check`` with the reader's complaints as a client sees them: ValueError naming
    the file (by ``name``), line and column, ``folder`` (the server's) left out."""
    try:
        return read_check(path, name)
    except UnicodeDecodeError as e:
        raise ValueError(f"{name}: not UTF-8 text (byte {e.start + 1})") from None
    except (ValueError, TypeError, OverflowError) as e:
        raise ValueError(str(e).replace(folder + os.sep, "").replace(folder, "")) from None


def check_file(jobs, path: str, name: str, folder: str, client: str | None = None) -> dict[str, Any]:
    """``read_summary`` in a check worker process (bsdflab.service.offload)."""
    return jobs.checker.run("fitdata", {"path": path, "name": name, "folder": folder}, name, client)


def read_dataset(request: dict[str, Any], out_dir: str) -> dict[str, Any]:
    """A fit request's data files read together with its sidecar, as its job reads them
    (bsdflab.fit.job.load_dataset), in a check worker: ValueError naming the file, line and
    column when they do not make a dataset; how many files they were."""
    from bsdflab.fit.job import check_inputs

    try:   # a structure fit's [[dataset]] uploads each as its job reads them
        check_inputs(request, Path(out_dir))
    except LookupError as e:   # an upload deleted since the route found it
        raise ValueError(str(e)) from None
    return {"files": len(request["data"])}


def upload(jobs, data: bytes, name: str, client: str, quota: int | None = None) -> dict[str, Any]:
    """Check and store one fit data file; its record ``{"hash", "format", "summary"}``.
    ValueError naming the file, line and column when it does not read; 413 past the quota."""
    with uploads.client_lock(client):
        return _upload(jobs, data, check_name("name", name), client, quota)


def _upload(jobs, data: bytes, name: str, client: str, quota: int | None) -> dict[str, Any]:
    h = hashlib.sha256(data).hexdigest()
    if quota is not None and not jobs.store.uploaded(h, client):
        stored = jobs.store.upload_bytes(client)
        if stored + len(data) > quota:
            raise HTTPException(413, quota_message(client, stored, len(data), quota))
    found = jobs.store.artefact(h, KIND)
    target = jobs.artefact_dir / f"{h}{SUFFIX}"
    if found is not None and target.is_file():
        jobs.store.put_upload(h, KIND, client, {"name": name}, found["result"])
        return found["result"]
    folder = tempfile.mkdtemp(dir=jobs.artefact_dir, prefix=".fitupload-")
    try:
        path = os.path.join(folder, name)
        Path(path).write_bytes(data)
        summary = check_file(jobs, path, name, folder, client)
        # after the reader: its complaint, the same as for bytes never uploaded, comes first
        # (before: another tenant's measured file answered this message, an existence oracle)
        if jobs.store.artefact(h) is not None:   # the same bytes stored as another kind (a measured file)
            raise ValueError(f"{name}: these bytes are stored as another kind of upload; they are not fit data")
        write_atomically(target, lambda tmp: shutil.copyfile(path, tmp), suffix=SUFFIX)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    result = {"hash": h, "format": summary["format"], "summary": {"bytes": len(data), **summary},
              "files": {"file": target.name}}
    jobs.store.put_upload(h, KIND, client, {"name": name}, result)
    return jobs.store.artefact(h, KIND)["result"]


def stored(jobs, content_hash: str) -> bool:
    row = jobs.store.artefact(content_hash, KIND)
    return row is not None and (jobs.artefact_dir / f"{content_hash}{SUFFIX}").is_file()


def size(jobs, content_hash: str) -> int:
    """Bytes of a stored fit data file."""
    return (jobs.artefact_dir / f"{content_hash}{SUFFIX}").stat().st_size
