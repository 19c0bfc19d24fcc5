"""Service configuration: the library's one settings model (bsdflab.util.settings) extended
with the server's fields, every field a ``BSDFLAB_*`` environment variable
(``BSDFLAB_DATA_DIR``, ``BSDFLAB_WORKERS``, ``BSDFLAB_API_KEYS``, ``BSDFLAB_LIMIT_QUEUE``...);
docs/settings.md is the table of them all.

Request caps are ``limit_*`` fields; a request beyond one is answered 4xx naming the cap
and its variable. They bound the work one HTTP request can ask of the server and sit below
the library's process-wide caps (``max_*``: ``limit_render_pixels`` <= ``max_pixels``,
``limit_table_cells`` <= ``max_table_cells``, checked when the settings are made).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import platformdirs
from pydantic import Field, SecretStr, model_validator
from pydantic_settings import SettingsConfigDict

from bsdflab.service.heavy import default_concurrency
from bsdflab.util.settings import LibrarySettings, variable


def _default_data_dir() -> Path:
    return Path(platformdirs.user_data_dir("bsdflab")) / "service"


class Settings(LibrarySettings):
    model_config = SettingsConfigDict(env_prefix="BSDFLAB_", extra="ignore", env_ignore_empty=True)

    host: str = Field("127.0.0.1", description="address to listen on (0.0.0.0: every interface)")
    port: int = Field(8000, ge=0, le=65535, description="port to listen on (0: a free one)")
    data_dir: Path = Field(default_factory=_default_data_dir,
                           description="SQLite job store and the content-addressed artefacts")
    workers: int | None = Field(None, ge=1, le=1024,
                                description="job worker processes (default: cores - 1, at most 4)")
    executor: str = Field("processes", description="processes, threads, dask:<address> or dask:local:N")
    api_key: SecretStr | None = Field(None, description="one admin key (X-API-Key or Bearer); with any key "
                                                        "set, every route but health, the page and the docs needs one")
    api_keys: dict[str, Any] = Field(default_factory=dict, description='named client keys as JSON: {"name": '
                                     '{"key": "...", "admin": false, "max_jobs": 8, "rate_per_s": 20}}')
    api_keys_file: Path | None = Field(None, description="a JSON file of named client keys (as api_keys)")
    key_rate_per_s: float | None = Field(20.0, gt=0, description="requests per second of a client key "
                                                                  "(bursts of twice that) unless its entry says")
    heavy_concurrency: int = Field(default_factory=default_concurrency, ge=1, le=1024,
                                   description="computing requests at once (429 beyond; default: the cores)")
    compute_deadline_s: float = Field(10.0, gt=0, le=3600, description="seconds one computing request may take")
    check_workers: int = Field(2, ge=1, le=64, description="processes that read clients' files (uploads, a "
                                                           "render's stored materials), started on the first")
    check_deadline_s: float = Field(60.0, gt=0, le=3600, description="seconds one check of a client's file may "
                                    "wait for a check worker (503 beyond), and then run (422 beyond)")
    limit_checks_per_key: int = Field(1, ge=1, description="checks of clients' files (uploads, a render's stored "
                                      "materials) one client key may have waiting or running (429 beyond)")

    limit_body_bytes: int = Field(4 << 20, ge=1024, description="request body size")
    limit_measured_bytes: int = Field(64 << 20, ge=1024, description="one measured-file upload, POST /v1/measured "
                                                                     "(its own body cap; a MERL file is 35 MB)")
    limit_json_containers: int = Field(1 << 15, ge=16, description="JSON arrays and objects in one request body "
                                       "(counted before parsing, which holds the GIL: about 2 us each; "
                                       "send many directions as angle lists, which are flat)")
    limit_store_refs: int = Field(16, ge=1, description="stored tables and measured files named by hash in one "
                                                        "request")
    limit_uploads_per_key: int = Field(2, ge=1, description="measured-file uploads of one client key at once")
    limit_upload_bytes_in_flight: int = Field(256 << 20, ge=1024, description="bytes of upload bodies being "
                                              "received, all clients (a body without Content-Length counts "
                                              "as BSDFLAB_LIMIT_MEASURED_BYTES)")
    limit_upload_storage_per_key: int = Field(1 << 30, ge=1024, description="bytes of stored uploads of one "
                                              "client key (the same bytes uploaded again cost nothing)")
    limit_check_memory_bytes: int = Field(1 << 30, ge=16 << 20, description="memory one check of a client's "
                                          "file (an upload, a render's stored material) may take in its worker")
    limit_directions: int = Field(100_000, ge=1, description="direction pairs per eval request")
    limit_samples: int = Field(65_536, ge=1, description="walks per direction pair (stochastic models)")
    limit_walks: int = Field(1 << 18, ge=1, description="direction pairs x walks per request "
                                                         "(2^18 walks of xenopeltis: about 14 CPU-seconds)")
    limit_response_bytes: int = Field(32 << 20, ge=1024, description="estimated size of one answer")
    limit_wavelengths: int = Field(1024, ge=1, description="wavelengths per request")
    limit_lobe_resolution: int = Field(181, ge=3, description="points of a lobe slice / side of a hemisphere grid")
    limit_angles: int = Field(256, ge=1, description="angles per thin-film request")
    limit_table_cells: int = Field(1 << 18, ge=1, description="cells of one table (both lobes counted)")
    limit_render_pixels: int = Field(1 << 22, ge=1, description="width x height of one render")
    limit_render_samples: int = Field(1 << 28, ge=1, description="width x height x spp of one render")
    limit_validation_level: Literal["quick", "standard", "full"] = Field(
        "standard", description="the highest validation level a request may ask for (full: hours)")
    limit_fit_walker_steps: int = Field(1 << 21, ge=1, description="walkers x max_steps of one fit (emcee), "
                                                                   "plus its MAP stage's evaluations")
    limit_fit_live_points: int = Field(2000, ge=4, description="live points of one fit (nested sampling)")
    limit_fit_emulator_solves: int = Field(1 << 14, ge=1, description="emulator_nodes ^ free parameters of one "
                                                                      "fit of the full model")
    limit_fit_files: int = Field(64, ge=1, description="uploaded data files of one fit")
    limit_event_streams_per_key: int = Field(8, ge=1, description="open progress streams (GET /v1/jobs/{id}/events) "
                                             "of one client key")
    limit_queue: int = Field(64, ge=1, description="queued + running jobs")
    limit_queue_reserve: int = Field(8, ge=0, description="queue slots a (non-admin) key that already has "
                                                          "jobs may not take: room for another key")
    limit_queue_per_key: int = Field(16, ge=1, description="queued + running jobs of one client key "
                                                           "unless its entry says (max_jobs)")

    log_level: Literal["critical", "error", "warning", "info", "debug"] = Field(
        "info", description="the service's and uvicorn's log level")
    log_format: Literal["text", "json"] = Field("text", description="text lines, or one JSON object a line")
    server_timeout_keep_alive_s: float = Field(5.0, gt=0, le=600, description="idle keep-alive connections close "
                                                                              "after this (uvicorn)")
    server_limit_concurrency: int = Field(512, ge=1, description="open connections and requests at once; 503 "
                                                                 "beyond, except /healthz")
    server_header_timeout_s: float = Field(10.0, gt=0, le=600, description="a connection that has not sent a "
                                           "whole request line and headers this long after it opened (or its "
                                           "last answer) is closed")
    server_read_timeout_s: float = Field(30.0, gt=0, le=3600, description="a request whose body stalls this "
                                         "long is closed")
    server_body_timeout_s: float = Field(600.0, gt=0, le=86400, description="a request whose body is not "
                                         "complete this long after its headers is closed (a body trickled a "
                                         "byte at a time never stalls)")
    server_max_header_bytes: int = Field(16 << 10, ge=1024, le=1 << 20, description="request line and headers "
                                                                                   "(h11; larger: 431/400)")
    server_backlog: int = Field(2048, ge=1, description="connections waiting to be accepted")

    model_cache_bytes: int = Field(256 << 20, ge=0, description="memory of the models kept built between "
                                                               "requests (a measured file's: about twice the file)")
    progress_interval_s: float = Field(0.25, gt=0, le=10, description="how often job progress is stored and streamed")

    @model_validator(mode="after")
    def _below_library_caps(self):
        for limit, cap in (("limit_render_pixels", "max_pixels"), ("limit_table_cells", "max_table_cells")):
            if getattr(self, limit) > getattr(self, cap):
                raise ValueError(f"{variable(limit)} ({getattr(self, limit)}) is above the library's cap "
                                 f"{variable(cap)} ({getattr(self, cap)}): a request could pass the first and "
                                 "fail in the worker")
        return self

    @property
    def db_path(self) -> Path:
        return self.data_dir / "jobs.sqlite"

    @property
    def artefact_dir(self) -> Path:
        return self.data_dir / "artefacts"


def limit_variable(field: str) -> str:
    return variable(field)


def markdown_table() -> str:
    """The table of every ``BSDFLAB_*`` variable (docs/settings.md is this output)."""
    rows = ["| variable | default | meaning |", "|---|---|---|"]
    for name, field in Settings.model_fields.items():
        if field.default_factory is not None:
            default = {"data_dir": "user data folder /service", "heavy_concurrency": "the cores"}.get(name, "unset")
        else:
            default = "unset" if field.default is None else f"`{field.default}`"
            if isinstance(field.default, int) and not isinstance(field.default, bool) and field.default >= 1 << 16:
                power = field.default.bit_length() - 1
                default = f"2^{power}" if field.default == 1 << power else default
        description = (field.description or "").replace("|", "\\|")
        rows.append(f"| `{variable(name)}` | {default} | {description} |")
    return "\n".join(rows)


if __name__ == "__main__":
    print(markdown_table())
