"""The Fit card's examples (service/static/fit_examples.json): each is its examples/fit TOML
with only [sampler] (and the full model's node counts) made small, names example files that
exist, and is a request POST /v1/fits accepts under the default limits once the page has put
the uploads' hashes in (the page swaps a [[dataset]]'s data name for its hash, as here)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest
import tomllib
from fastapi import HTTPException

from bsdflab.fit import job as fit_job
from bsdflab.service import Settings
from bsdflab.service.routers.fits import check_limits

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = json.loads((ROOT / "service" / "static" / "fit_examples.json").read_text())


def by_hash(config: dict, hashes: dict[str, str]) -> dict:
    """What fit.js's byHash sends: each [[dataset]]'s data name replaced by its upload's hash."""
    if not isinstance(config.get("dataset"), list):
        return config
    return {
        **config,
        "dataset": [
            {**{k: v for k, v in e.items() if k != "data"}, "hash": hashes[e["data"]]} for e in config["dataset"]
        ],
    }


@pytest.mark.parametrize("example", EXAMPLES, ids=[e["id"] for e in EXAMPLES])
def test_an_example_is_its_toml_made_small_and_is_accepted(example):
    files = [ROOT / f for f in example["files"]]
    assert all(f.is_file() for f in files), example["files"]
    if example["source"]:
        want = tomllib.loads((ROOT / example["source"]).read_text())
        got = dict(example["config"])
        assert set(got["sampler"]) <= {"walkers", "max_steps", "check_every", "map_starts", "seed"}
        want.pop("sampler"), got.pop("sampler")
        if want.get("model", {}).get("kind") == "full":  # fewer emulator nodes and solver nodes only
            for k in ("nodes", "emulator_nodes", "emulator_checks"):
                want["model"].pop(k, None), got["model"].pop(k, None)
        assert got == want, example["id"]
    if example["id"] == "wide":  # the wide CSV's sidecar is the one shipped beside it
        assert example["sidecar"] == tomllib.loads((ROOT / "examples/fit/wide/angles.csv.toml").read_text())
    hashes = {f.name: hashlib.sha256(f.read_bytes()).hexdigest() for f in files}
    body = {
        "config": by_hash(example["config"], hashes),
        "data": [{"hash": h, "name": n} for n, h in hashes.items()],
        "sidecar": example["sidecar"],
    }
    try:
        check_limits(Settings(), fit_job.normalise(body))
    except HTTPException as e:  # the limit's 422, with its message
        pytest.fail(f"{example['id']}: {e.detail}")
