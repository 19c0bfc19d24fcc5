"""Service configuration: pydantic-settings, every field a ``BSDFLAB_*`` environment variable
(``BSDFLAB_DATA_DIR``, ``BSDFLAB_WORKERS``, ``BSDFLAB_API_KEY``, ``BSDFLAB_LIMIT_QUEUE``...).

Request caps are ``limit_*`` fields; a request beyond one is answered 4xx naming the cap
and its variable. They bound the work one request can ask of the server, independently of
the Python API's own resource caps (bsdflab.util.limits).
"""
from __future__ import annotations

from pathlib import Path

import platformdirs
from pydantic import Field, SecretStr
from pydantic_settings import BaseSettings, SettingsConfigDict


def _default_data_dir() -> Path:
    return Path(platformdirs.user_data_dir("bsdflab")) / "service"


class Settings(BaseSettings):
    model_config = SettingsConfigDict(env_prefix="BSDFLAB_", extra="ignore")

    host: str = "127.0.0.1"
    port: int = Field(8000, ge=0, le=65535)
    data_dir: Path = Field(default_factory=_default_data_dir,
                           description="SQLite job store and the content-addressed artefacts")
    workers: int | None = Field(None, ge=1, le=1024,
                                description="job worker processes (default: cores - 1, at most 4)")
    executor: str = Field("processes", description="processes, threads, dask:<address> or dask:local:N")
    api_key: SecretStr | None = Field(None, description="when set, required (X-API-Key or Bearer) "
                                                        "by every endpoint that computes, starts or deletes")

    limit_body_bytes: int = Field(4 << 20, ge=1024, description="request body size")
    limit_directions: int = Field(100_000, ge=1, description="direction pairs per eval request")
    limit_samples: int = Field(65_536, ge=1, description="walks per direction pair (stochastic models)")
    limit_walks: int = Field(1 << 24, ge=1, description="direction pairs x walks per request")
    limit_wavelengths: int = Field(1024, ge=1, description="wavelengths per request")
    limit_lobe_resolution: int = Field(181, ge=3, description="points of a lobe slice / side of a hemisphere grid")
    limit_angles: int = Field(256, ge=1, description="angles per thin-film request")
    limit_table_cells: int = Field(1 << 18, ge=1, description="cells of one table (both lobes counted)")
    limit_render_pixels: int = Field(1 << 22, ge=1, description="width x height of one render")
    limit_render_samples: int = Field(1 << 28, ge=1, description="width x height x spp of one render")
    limit_queue: int = Field(64, ge=1, description="queued + running jobs")

    progress_interval_s: float = Field(0.25, gt=0, le=10, description="how often job progress is stored and streamed")

    @property
    def db_path(self) -> Path:
        return self.data_dir / "jobs.sqlite"

    @property
    def artefact_dir(self) -> Path:
        return self.data_dir / "artefacts"


def limit_variable(field: str) -> str:
    return f"BSDFLAB_{field.upper()}"
