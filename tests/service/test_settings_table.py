"""One settings model, one table: docs/settings.md lists every BSDFLAB_* variable, and no
module reads the environment for one behind the model's back."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from bsdflab.service.settings import Settings, markdown_table

ROOT = Path(__file__).resolve().parents[2]


def test_the_docs_table_is_the_models():
    assert markdown_table() in (ROOT / "docs" / "settings.md").read_text()


def test_no_module_reads_a_bsdflab_variable_itself():
    """Before: 29 variables were read in 6 places (os.environ in limits, signing, cache,
    the Mitsuba variant), two of them with different caps for the same quantity."""
    offenders = []
    for folder in ("bsdflab", "service", "reference"):
        for path in (ROOT / folder).rglob("*.py"):
            text = path.read_text()
            if re.search(r"(os\.environ|getenv)[^\n]*BSDFLAB_|(os\.environ|getenv)[^\n]*ENV_VAR", text):
                offenders.append(str(path.relative_to(ROOT)))
    assert offenders == []


def test_a_request_limit_above_the_library_cap_is_refused():
    with pytest.raises(ValueError, match="BSDFLAB_LIMIT_RENDER_PIXELS.*BSDFLAB_MAX_PIXELS"):
        Settings(limit_render_pixels=1 << 27)
