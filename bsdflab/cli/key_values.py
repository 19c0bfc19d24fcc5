"""`K=V` command-line options (`render --option`, `export --set`) as a dict."""
from __future__ import annotations

import json


def key_values(pairs: list[str], option: str) -> dict:
    """{K: V} with each V parsed as JSON, else kept as a bare string; ValueError naming
    ``option`` for an item without '=' or key."""
    out = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise ValueError(f"{option} must be KEY=VALUE, got {pair!r}")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            out[key] = value  # a bare string
    return out
