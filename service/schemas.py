"""Request and response bodies (pydantic). Requests forbid unknown fields; physical
ranges are checked by the Python API, whose ValueError becomes a 422 naming the field."""
from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, Strict, field_validator, model_validator
from pydantic.json_schema import SkipJsonSchema

from bsdflab.validation.registry import FAMILIES


def _integral(value):
    """JSON Schema counts 3.0 as an integer; a bool or a string is not one."""
    return int(value) if isinstance(value, float) and value.is_integer() else value


def _brief(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _numbers(value: Any) -> Any:
    """A list of numbers checked in one pass, stopping at the first bad item: pydantic would
    build one error per bad item (100 000 of them: an 18 MB answer, seconds of work)."""
    if isinstance(value, list):
        for i, item in enumerate(value):
            if type(item) not in (int, float):   # strict: a bool is not a number
                raise ValueError(f"item {i} is {_brief(item)}, not a number")
    return value


def _vectors(value: Any) -> Any:
    """A list of 3-vectors checked in one pass (as ``_numbers``)."""
    if isinstance(value, list):
        for i, item in enumerate(value):
            if type(item) is not list or len(item) != 3 or any(type(x) not in (int, float) for x in item):
                raise ValueError(f"item {i} is {_brief(item)}, not a vector of 3 numbers")
    return value


# Integers are strict (true/false and "3" are refused: a seed of false was 0), except that
# an integral number such as 3.0 is one, as JSON Schema says.
Int = Annotated[int, BeforeValidator(_integral), Strict()]
Seed = Annotated[Int, Field(ge=0, lt=1 << 64, description="random seed (uint64)")]
Count = Annotated[Int, Field(ge=1, le=1 << 24)]
Vector3 = Annotated[list[float], Field(min_length=3, max_length=3)]
Floats = Annotated[list[float], BeforeValidator(_numbers), Field(min_length=1)]
Vectors = Annotated[list[Vector3], BeforeValidator(_vectors), Field(min_length=1)]
HASH_PATTERN = r"^[0-9a-f]{64}$"
JOB_ID_PATTERN = r"^[0-9a-f]{32}$"


class Request(BaseModel):
    # strict: a bool is neither a number nor an integer ([false] was the angle 0)
    model_config = ConfigDict(extra="forbid", strict=True)

    @model_validator(mode="before")
    @classmethod
    def _known_fields(cls, data: Any) -> Any:
        """Unknown fields as one error (extra="forbid" makes one per field)."""
        if isinstance(data, dict):
            unknown = [k for k in data if k not in cls.model_fields]
            if unknown:
                names = ", ".join(_brief(k) for k in unknown[:5]) + (", ..." if len(unknown) > 5 else "")
                raise ValueError(f"{len(unknown)} unknown fields: {names} (known: {', '.join(cls.model_fields)})")
        return data


ONE_OF = [{"required": ["model"], "not": {"required": ["preset"]}},
          {"required": ["preset"], "not": {"required": ["model"]}}]


def whole(example: dict[str, Any], exclusive: bool = True) -> ConfigDict:
    """A request's config with a complete example (a client, or schemathesis, can send it as
    is; field examples alone combine into requests that name both a model and a preset)."""
    extra = {"examples": [example], **({"oneOf": ONE_OF} if exclusive else {})}
    return ConfigDict(extra="forbid", strict=True, json_schema_extra=extra)


class ModelSpec(Request):
    """A model: its ``to_dict`` form, or a preset name and keyword overrides (exactly one of
    ``model`` and ``preset``, as the schema's ``oneOf`` says). A table is named by its hash,
    ``{"type": "table", "hash": ...}``: no request names a server path."""

    model_config = ConfigDict(extra="forbid", strict=True, json_schema_extra={"oneOf": ONE_OF})

    model: dict[str, Any] | SkipJsonSchema[None] = Field(None, description="a BSDF dict (BSDF.to_dict form)",
                                                         examples=[{"type": "diffuse", "reflectance": 0.5}])
    preset: Annotated[str, Field(min_length=1)] | SkipJsonSchema[None] = Field(
        None, description="a preset name (GET /v1/presets)", examples=["xenopeltis"])
    overrides: dict[str, Any] | None = Field(None, description="the preset's keyword parameters",
                                             examples=[{"film_thickness_nm": 450}])

    @model_validator(mode="after")
    def _no_explicit_null(self):
        # the schema says a dict / a name: "model": null beside a preset is not "left out"
        for name in ("model", "preset"):
            if name in self.model_fields_set and getattr(self, name) is None:
                wanted = "a BSDF dict" if name == "model" else "a preset name"
                raise ValueError(f"{name} is null: leave it out, or give {wanted}")
        return self

    def spec(self) -> dict[str, Any]:
        return {"model": self.model, "preset": self.preset, "overrides": self.overrides}


class Error(BaseModel):
    detail: Any = Field(description="what was wrong (for 422: the field and the valid range)")


# -- BSDF queries ----------------------------------------------------------------------------
class EvalRequest(ModelSpec):
    model_config = whole({"preset": "xenopeltis", "theta_i": [30.0], "theta_o": [20.0, 45.0], "samples": 16})
    wi: Vectors | None = Field(
        None, description="incident unit vectors (N, 3) or one")
    wo: Vectors | None = Field(
        None, description="outgoing unit vectors (N, 3) or one")
    theta_i: Floats | None = Field(None, description="incidence angles in degrees [0, 90]")
    theta_o: Floats | None = Field(None, description="outgoing angles in degrees [0, 180] (> 90: below)")
    phi: Floats | None = Field(None, description="azimuth phi_o - phi_i in degrees (mirror at 180)")
    wavelengths: Floats | None = Field(None, description="nm; omit for linear sRGB (D65)")
    samples: Count | None = Field(None, description="walks per pair for stochastic models (default: the model's)")
    seed: Seed | None = Field(None, description="seed of the walks (default: the model's)")
    thickness_nm: Floats | None = Field(None, description="the thin film's total thickness in nm per pair (or one), "
                                                          "replacing the model's for this query")


class EvalResponse(BaseModel):
    channels: list[str]
    wi: list[list[float]]
    wo: list[list[float]]
    values: list[list[float | None]] = Field(description="f(wi, wo) |cos theta_o| per pair and channel")
    stderr: list[list[float | None]] | None = Field(description="standard errors (stochastic models), else null")
    stochastic: bool


class LobeRequest(ModelSpec):
    model_config = whole({"model": {"type": "diffuse", "reflectance": 0.5}, "theta_i": 30.0, "points": 9,
                          "resolution": 9})
    theta_i: float = Field(30.0, description="incidence angle in degrees [0, 90)")
    view: Literal["plane", "hemisphere", "both"] = "both"
    points: Int = Field(91, ge=3, description="points along the plane of incidence")
    resolution: Int = Field(32, ge=3, description="side of the hemisphere grid")
    samples: Count | None = Field(None, description="walks per direction for stochastic models")
    seed: Seed | None = None


class PlaneView(BaseModel):
    angle_deg: list[float] = Field(description="signed outgoing angle in the plane (mirror at +theta_i)")
    values: list[list[float | None]] = Field(description="f |cos theta_o|, linear sRGB")
    stderr: list[list[float | None]] | None


class HemisphereView(BaseModel):
    x: list[float]
    y: list[float]
    rgb: list[list[list[float | None] | None]] = Field(description="[row y][column x] linear sRGB, null outside")
    luminance: list[list[float | None]]
    luminance_stderr: list[list[float | None]] | None


class LobeResponse(BaseModel):
    theta_i: float
    wi: list[float]
    model: dict[str, Any]
    stochastic: bool
    plane: PlaneView | None = None
    hemisphere: HemisphereView | None = None


class ThinFilmRequest(Request):
    model_config = whole({"thickness_nm": 400.0, "angles": [0.0, 45.0], "wavelengths": [450.0, 550.0, 650.0]},
                         exclusive=False)
    ext_ior: float = Field(1.000277, description="index of the medium light comes from (default air)")
    film_ior: float = Field(1.83, description="film index (default guanine)")
    thickness_nm: float = Field(400.0, description="film thickness in nm")
    substrate_ior: float = Field(1.5515, description="substrate index (default keratin at 550 nm)")
    angles: Floats | None = Field(None, description="incidence angles in degrees (default 0, 5, ... 85)")
    wavelengths: Floats | None = Field(None, description="nm (default 380, 385, ... 780)")
    layers: Annotated[list[FilmLayer], Field(min_length=1, max_length=64)] | None = Field(
        None, description="a film stack, top first, instead of film_ior and thickness_nm",
        examples=[[{"ior": 2.3, "thickness_nm": 60}, {"ior": 1.38, "thickness_nm": 100}]])


class FilmLayer(Request):
    ior: float = Field(description="the layer's (real) refractive index")
    thickness_nm: float = Field(description="its thickness in nm")


class ThinFilmResponse(BaseModel):
    angles: list[float]
    wavelengths: list[float]
    reflectance: list[list[float]] = Field(description="[angle][wavelength], unpolarised")
    transmittance: list[list[float]]
    rgb: list[list[float]] = Field(description="reflected colour per angle, linear sRGB (D65)")
    srgb: list[str] = Field(description="the same colours for display: #rrggbb, one exposure for all")
    exposure: float


# -- catalogues ------------------------------------------------------------------------------
class PresetInfo(BaseModel):
    name: str
    description: str
    parameters: dict[str, Any]
    model: dict[str, Any]


class SceneInfo(BaseModel):
    name: str
    description: str
    parameters: dict[str, Any]


# -- jobs ------------------------------------------------------------------------------------
class JobInfo(BaseModel):
    id: str
    kind: str
    hash: str = Field(description="content hash of the request: the artefact's name")
    state: Literal["queued", "running", "done", "failed", "cancelled"]
    progress: float
    elapsed_s: float
    eta_s: float | None
    created: float
    started: float | None
    finished: float | None
    attempts: int
    cancel_requested: bool = False
    error: str | None = None
    error_type: str | None = None
    links: dict[str, str]


class JobList(BaseModel):
    jobs: list[JobInfo]


class TableRequest(ModelSpec):
    model_config = whole({"model": {"type": "diffuse", "reflectance": 0.5},
                          "grid": {"n_theta_i": 2, "n_theta_o": 4, "n_phi": 3}})
    grid: dict[str, Any] | None = Field(None, description="n_theta_i, n_theta_o, n_phi, thickness_nm",
                                        examples=[{"n_theta_i": 4, "n_theta_o": 8, "n_phi": 5}])
    rel_error: float = Field(0.01, description="target: the 95th percentile over the cells of each cell's "
                                               "relative error of luminance (docs/table_format.md)")
    wavelengths: Floats | None = None
    min_samples: Count = 512
    max_samples: Count = 65536
    seed: Seed = 0
    method: Literal["auto", "pfmc", "adding-doubling"] = Field(
        "auto", description="auto: adding-doubling wherever it covers the model (reflecting layered stacks), "
                            "else pfmc; pfmc (Monte Carlo) or adding-doubling (deterministic; the walk "
                            "settings do not apply) to choose")
    nodes: int | None = Field(None, ge=4, le=256, description="adding-doubling: nodes per cosine panel")
    orders: int | None = Field(None, ge=1, le=4096, description="adding-doubling: Fourier orders")


class TableInfo(BaseModel):
    hash: str
    model: dict[str, Any]
    grid: dict[str, Any]
    lobes: list[str]
    channels: list[str]
    split_direct: bool
    rel_error_target: float
    error: dict[str, float] = Field(description="relative standard error of the luminance: rms, p95, max")
    samples: dict[str, float]
    meta: dict[str, Any]
    content_hash: str
    bytes: int
    links: dict[str, str]


class TableList(BaseModel):
    tables: list[TableInfo]


class RenderRequest(Request):
    model_config = whole({"scene": "furnace", "width": 8, "height": 8, "spp": 1}, exclusive=False)
    scene: str = Field(min_length=1, description="a scene name (GET /v1/scenes)", examples=["sphere"])
    options: dict[str, Any] = Field(default_factory=dict, description="the scene's own keywords",
                                    examples=[{"variant": "diffuse"}])
    width: Int = Field(320, ge=1, le=16384)
    height: Int = Field(180, ge=1, le=16384)
    spp: Int = Field(16, ge=1, le=1 << 20)
    seed: Seed = 0
    max_depth: Int | None = Field(None, ge=1, le=1024)
    lights: list[dict[str, Any]] | None = Field(
        None, max_length=64, description="lights added to the scene's own: point, spot, directional or sun "
        "(docs/scene_format.md, Lights)",
        examples=[[{"type": "sun", "elevation_deg": 35, "azimuth_deg": -40}]])

    @field_validator("lights")
    @classmethod
    def _lights(cls, value):
        from bsdflab.render.lights import lights_of

        if value:
            lights_of(value)  # a bad light is a 422 naming its field
        return value


class RenderInfo(BaseModel):
    hash: str
    state: Literal["queued", "running", "done", "failed", "cancelled"]
    request: dict[str, Any]
    job: JobInfo | None
    summary: dict[str, str] | None
    links: dict[str, str]


class ValidationRequest(Request):
    model_config = whole({"level": "quick", "only": "tables/diffuse-exact"}, exclusive=False)
    level: Literal["quick", "standard", "full"] = Field("quick", description="effort, as bsdflab validate --level")
    only: Annotated[str, Field(min_length=1, max_length=200)] | None = Field(
        None, description="only checks whose name matches this glob or contains it", examples=["tables/"])
    families: Annotated[list[Literal[FAMILIES]], Field(min_length=1, max_length=len(FAMILIES))] | None = Field(
        None, description="only checks of these families (GET /v1/validations/families lists them)",
        examples=[["solvers", "coverage"]])
    benchmarks: bool = Field(False, description="also run the benchmarks (minutes)")


class ValidationFamily(BaseModel):
    name: str
    checks: int = Field(description="checks registered in this family")


class ValidationInfo(BaseModel):
    hash: str
    state: Literal["queued", "running", "done", "failed", "cancelled"]
    request: dict[str, Any]
    job: JobInfo | None
    summary: dict[str, int] | None = Field(description="checks by status: pass, fail, error, skipped, study, total")
    exit_status: int | None = Field(description="1 when a check failed or errored (as bsdflab validate)")
    links: dict[str, str]


FIT_EXAMPLE = {
    "config": {"parameters": {"film_thickness_nm": {"prior": "normal", "mean": 430.0, "sd": 10.0},
                              "film_ior": {"prior": "normal", "mean": 1.83, "sd": 0.02}},
               "model": {"thickness_nodes": 1},
               "sampler": {"walkers": 8, "max_steps": 200, "check_every": 50, "map_starts": 1},
               "appearance": {"draws": 4, "renders": 0, "angles_deg": [0, 30]}},
    "data": [{"hash": "0" * 64, "name": "data.csv"}]}


class FitFile(Request):
    hash: Annotated[str, Field(pattern=HASH_PATTERN, description="an upload's hash (POST /v1/fits/datasets)")]
    name: Annotated[str, Field(min_length=1, max_length=128, description="the file's name as the readers see "
                                                                         "it: its suffix tells the format, an "
                                                                         "angle in it places the curve")]


class FitRequest(Request):
    model_config = whole(FIT_EXAMPLE, exclusive=False)
    config: dict[str, Any] = Field(description="the fit's TOML (docs/fit_data.md) as JSON: [parameters], "
                                               "[sampler], [model], [appearance]; or a [structure] fit's, its "
                                               "[[dataset]] uploads named by hash (docs/fit.md)")
    data: Annotated[list[FitFile], Field(min_length=1, max_length=256)] = Field(
        description="the uploaded data files: one long CSV, or spectra files with an import sidecar")
    sidecar: dict[str, Any] | None = Field(None, description="the import sidecar's TOML as JSON (wide CSV, "
                                                             "instrument spectra; docs/fit_data.md)")


class FitInfo(BaseModel):
    hash: str
    state: Literal["queued", "running", "done", "failed", "cancelled"]
    request: dict[str, Any]
    job: JobInfo | None
    summary: dict[str, Any] | None = Field(description="rows, free parameters, sampler, convergence, posterior "
                                                       "mean, MAP, predictive checks and warnings; a structure "
                                                       "fit's parameter table (summary.json has everything)")
    files: list[str] | None = Field(description="the study's files: GET /v1/fits/{hash}/files/{name}")
    links: dict[str, str]


class FitDataInfo(BaseModel):
    hash: str = Field(description="SHA-256 of the file's bytes: name it in a fit's data as {\"hash\", \"name\"}")
    format: str = Field(description="the format the readers found (long, wide, procspec, ...)")
    summary: dict[str, Any] = Field(description="bytes, and rows (long CSV), curves (spectra) or lines (wide CSV)")


class FitDataList(BaseModel):
    datasets: list[FitDataInfo]


class Health(BaseModel):
    status: Literal["ok"]


class VersionInfo(BaseModel):
    bsdflab: str
    core: dict[str, Any]
    mitsuba: str | None
    python: str
    executor: str
    workers: int
    api_key_required: bool
    limits: dict[str, int]


class MeasuredInfo(BaseModel):
    hash: str = Field(description="SHA-256 of the file's bytes: name it in a model as "
                                  '{"type": "measured" or "merl", "hash": ...}')
    format: str = Field(description="rgl (an RGL .bsdf file) or merl (a MERL .binary file)")
    summary: dict[str, Any] = Field(description="bytes, channels, and the RGL grid and header description")


class MeasuredList(BaseModel):
    measured: list[MeasuredInfo]
