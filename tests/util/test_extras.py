"""A missing optional dependency names the extra that installs it (bsdflab.util.extras)."""
from __future__ import annotations

import subprocess
import sys

import pytest

from bsdflab.util.extras import require


def test_require_names_the_extra():
    with pytest.raises(ImportError, match=r"comes with bsdflab's 'dask' extra: pip install 'bsdflab\[dask\]'"):
        require("bsdflab_no_such_module", "dask")
    assert require("json", "core").dumps([]) == "[]"


@pytest.mark.parametrize("blocked, module, extra", [
    ("distributed", "bsdflab.distributed", "dask"),
    ("fastapi", "bsdflab.service", "service"),
    ("emcee", "bsdflab.fit", "fit"),
    ("dynesty", "bsdflab.fit", "fit"),
])
def test_a_package_without_its_extra_says_which_to_install(blocked, module, extra):
    """In a fresh interpreter where ``blocked`` cannot be imported (None in sys.modules is
    what Python reports as not installed), importing ``module`` names the extra."""
    code = (f"import sys\nsys.modules[{blocked!r}] = None\n"
            f"try:\n    import {module}\nexcept ImportError as e:\n    print(e)\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert f"pip install 'bsdflab[{extra}]'" in p.stdout
