"""Requests that would exhaust memory are refused before allocating, with a clear error.

Each huge case runs in a fresh interpreter whose address space is capped with
``resource.setrlimit(RLIMIT_AS)`` at 1.5 GiB above what it has mapped after importing
bsdflab, so a case that allocated before checking would die with MemoryError /
std::bad_alloc (or be killed) instead of printing the refusal. Before the caps each of
these allocated: the 512^3 grid (~9.5 GB per thickness node), snake_body at its documented
maxima (a 6 GiB array), a 4096 x 4096 torus (Embree out of memory), iridophore_stack(10**7)
(a 20-million-element list), a 16384 x 4096 render (10 GB).
"""
from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

HEADROOM = 3 << 29  # 1.5 GiB

RUNNER = textwrap.dedent("""
    import resource, sys
    import bsdflab, bsdflab.render, bsdflab.scenes, bsdflab.tables  # imports first: their mappings
    from bsdflab.render.geometry import build_mesh
    with open("/proc/self/status") as f:
        vm = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmSize:"))
    resource.setrlimit(resource.RLIMIT_AS, (vm + {headroom}, vm + {headroom}))
    try:
        {call}
    except ValueError as e:
        print("REFUSED:", e)
        sys.exit(0)
    except MemoryError:
        print("MEMORY ERROR")
        sys.exit(3)
    print("ACCEPTED")
    sys.exit(4)
""")

CASES = {
    "table grid 512^3": "bsdflab.tables.TableGrid(512, 512, 512)",
    "table grid with thickness nodes": "bsdflab.tables.TableGrid(128, 256, 256, tuple(range(100, 300)))",
    "table from a cache request": ("bsdflab.tables.cached_table({'type': 'diffuse'}, "
                                   "bsdflab.tables.TableGrid(256, 256, 256), 0.1, [400 + i for i in range(40)], "
                                   "lambda: None, directory='/tmp')"),
    "tabulate on a grid at the cell cap": ("bsdflab.tables.tabulate(bsdflab.Diffuse(), "
                                           "bsdflab.tables.TableGrid(256, 256, 512), progress=False)"),
    "snake_body at its maxima": "build_mesh({'type': 'snake_body', 'segments': 200000, 'sides': 4096})",
    "snake_head at its maxima": ("build_mesh({'type': 'snake_head', 'segments': 16, 'head_segments': 20000, "
                                 "'sides': 4096})"),
    "torus 4096 x 4096": "build_mesh({'type': 'torus', 'resolution': 4096, 'minor_resolution': 4096})",
    "sphere 4096": "build_mesh({'type': 'sphere', 'subdivisions': 4096})",
    "iridophore_stack(10**7)": "bsdflab.presets.iridophore_stack(10**7)",
    "render 16384 x 4096": ("bsdflab.render.render(bsdflab.scenes.scene('furnace', width=16384, height=4096), "
                            "spp=1, progress=False)"),
}


@pytest.mark.parametrize("name", CASES)
def test_huge_request_is_refused_before_allocating(name):
    code = RUNNER.format(headroom=HEADROOM, call=CASES[name])
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                         env={"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "PATH": "/usr/bin:/bin",
                              "BSDFLAB_THREADS": "2"})
    assert out.returncode == 0 and out.stdout.startswith("REFUSED:"), (out.returncode, out.stdout, out.stderr[-3000:])
    message = out.stdout.splitlines()[0]
    if name.startswith("iridophore"):  # a structural bound (the core's 32 film layers), not a cap
        assert "platelets must be an integer in [1, 16]" in message, message
    else:  # says which cap, and how to raise it
        assert "cap" in message and "BSDFLAB_MAX_" in message, message


def test_caps_are_configurable(monkeypatch):
    from bsdflab.render import Camera
    from bsdflab.render.geometry import build_mesh
    from bsdflab.util import limits

    monkeypatch.setenv("BSDFLAB_MAX_PIXELS", "1_000")
    with pytest.raises(ValueError, match="BSDFLAB_MAX_PIXELS"):
        Camera(width=40, height=30)
    assert Camera(width=40, height=25).width == 40
    monkeypatch.setenv("BSDFLAB_MAX_BYTES", "1M")
    with pytest.raises(ValueError, match="more than the cap of 1 MiB"):
        build_mesh({"type": "sphere", "subdivisions": 256})
    monkeypatch.setenv("BSDFLAB_MAX_BYTES", "lots")
    with pytest.raises(ValueError, match="BSDFLAB_MAX_BYTES must be a positive integer"):
        limits.current()
    monkeypatch.delenv("BSDFLAB_MAX_BYTES")
    assert limits.current().max_bytes == 4 << 30
