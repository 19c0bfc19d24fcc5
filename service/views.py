"""Store rows -> response models, with the links a client follows next."""
from __future__ import annotations

from typing import Any

from bsdflab.service.schemas import JobInfo

KIND_PATHS = {"tabulate": "tables", "render": "renders", "validate": "validations", "fit": "fits"}


def job_links(row: dict[str, Any]) -> dict[str, str]:
    links = {"self": f"/v1/jobs/{row['id']}", "events": f"/v1/jobs/{row['id']}/events"}
    resource = KIND_PATHS.get(row["kind"])
    if resource is not None:
        links["artefact"] = f"/v1/{resource}/{row['hash']}"
    return links


def job_info(row: dict[str, Any]) -> JobInfo:
    return JobInfo(id=row["id"], kind=row["kind"], hash=row["hash"], state=row["state"],
                   progress=row["progress"], elapsed_s=row["elapsed"], eta_s=row["eta"],
                   created=row["created"], started=row["started"], finished=row["finished"],
                   attempts=row["attempts"], cancel_requested=bool(row.get("cancel_requested", False)),
                   error=row["error"], error_type=row["error_type"], links=job_links(row))
