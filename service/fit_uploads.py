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

import os
import zipfile
from pathlib import Path
from typing import Any

from bsdflab.fit.job import SUFFIX, check_name
from bsdflab.fit.readers.oceanoptics_procspec import check_sizes
from bsdflab.service import uploads

KIND = "fitdata"
TEXT_ONLY = ("wide",)        # formats whose reading needs the fit request's sidecar


def check_zip(path: str, name: str) -> None:
    """A zip's declared sizes (the ProcSpec reader checks them again whatever the name)."""
    try:
        with zipfile.ZipFile(path) as z:
            infos = z.infolist()
    except (zipfile.BadZipFile, OSError, EOFError, UnicodeDecodeError) as e:   # a name flagged UTF-8 that is not
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


async def upload(jobs, data: bytes, name: str, client: str, quota: int | None = None) -> dict[str, Any]:
    """Check and store one fit data file; its record ``{"hash", "format", "summary"}``.
    ValueError naming the file, line and column when it does not read; 413 past the quota.
    Awaited on the event loop (bsdflab.service.uploads.stored_after_check)."""
    name = check_name("name", name)
    async with uploads.client_turn(client):
        return await uploads.stored_after_check(jobs, data, client, quota, uploads.UploadKind(
            KIND, SUFFIX, {"name": name}, name,
            check=lambda path, folder: ("fitdata", {"path": path, "name": name, "folder": folder}, name),
            record=lambda summary: {"format": summary["format"], "summary": {"bytes": len(data), **summary}},
            reusable=lambda row: _suffix(row["request"].get("name", "")) == _suffix(name)))


def _suffix(name: str) -> str:
    """What picks a file's reader with its contents (bsdflab.fit.readers.reader_for): the
    same bytes under a name of another suffix are read again (a stored file answering any
    name told whether anyone had uploaded those bytes)."""
    return os.path.splitext(name)[1].lower()


def stored(jobs, content_hash: str) -> bool:
    row = jobs.store.artefact(content_hash, KIND)
    return row is not None and (jobs.artefact_dir / f"{content_hash}{SUFFIX}").is_file()


def size(jobs, content_hash: str) -> int:
    """Bytes of a stored fit data file."""
    return (jobs.artefact_dir / f"{content_hash}{SUFFIX}").stat().st_size
