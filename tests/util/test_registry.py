"""The BSDF registry finds every type whatever was imported first (lazy entries for types
defined above bsdflab.bsdfs), checked in fresh interpreters."""
from __future__ import annotations

import json
import subprocess
import sys

import bsdflab as bl
from bsdflab.bsdfs.base import BSDF, TYPES
from bsdflab.tables import TableGrid, tabulate, write_table


def _all_subclasses(cls):
    for sub in cls.__subclasses__():
        yield sub
        yield from _all_subclasses(sub)


def _fresh(code: str) -> str:
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    return p.stdout.strip()


def test_every_type_defined_above_bsdfs_has_a_lazy_entry():
    import bsdflab.tables  # noqa: F401 -- every module that defines a type

    # comparison models of bsdflab.reference register when their module is imported: they
    # are never product materials, so from_dict need not find them unasked
    above = {c.type_name: c.__module__ for c in _all_subclasses(BSDF)
             if c.__dict__.get("type_name") and not c.__module__.startswith(("bsdflab.bsdfs.", "bsdflab.reference."))}
    assert above and {name: TYPES.lazy().get(name) for name in above} == above


def test_a_subclass_inheriting_a_type_name_does_not_take_the_type_over():
    """Before: a test's mutant (``class High(Measured)``, 1 % high) registered itself as
    "measured", and every later ``{"type": "measured"}`` in the process read 1 % high."""
    from bsdflab.measured import Measured

    class Wrapper(Measured):
        pass

    assert TYPES.get("measured") is Measured and Wrapper.type_name == "measured"


def test_a_table_from_its_dict_without_importing_tables_first(tmp_path):
    path = tmp_path / "t.exr"
    write_table(path, tabulate(bl.Diffuse(0.5), TableGrid(3, 4, 3), progress=False))
    out = _fresh(
        "import sys\n"
        "from bsdflab.bsdfs.base import TYPES, from_dict\n"
        "before = 'bsdflab.tables.table_bsdf' in sys.modules\n"
        f"b = from_dict({{'type': 'table', 'path': {str(path)!r}}})\n"
        "print(before, type(b).__name__, all(TYPES.get(n) is not None for n in TYPES.names()))\n")
    assert out == "False TableBSDF True"


def test_a_layered_model_from_its_dict_in_a_fresh_interpreter():
    d = bl.presets.xenopeltis().to_dict()
    out = _fresh(f"import json\nfrom bsdflab.bsdfs.base import from_dict\n"
                 f"print(from_dict(json.loads({json.dumps(d)!r})).type_name)")
    assert out == "layered"
