"""Where a report came from: versions, git commit, core build flags, machine, command."""
from __future__ import annotations

import os
import platform
import re
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

PACKAGES = ("bsdflab", "mitsuba", "drjit", "tmm", "colour-science", "numpy", "scipy", "matplotlib",
            "flip-evaluator")
REPO = Path(__file__).resolve().parents[2]


def _version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def _git(*args: str) -> str | None:
    try:
        out = subprocess.run(["git", *args], cwd=REPO, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def core_build() -> dict[str, str]:
    """Build type, compiler and flags from the CMake cache of the build in this checkout
    (editable installs build into build/<wheel tag>/), else what CMakeLists.txt declares."""
    info: dict[str, str] = {}
    for cache in sorted(REPO.glob("build/*/CMakeCache.txt")):
        for line in cache.read_text(errors="replace").splitlines():
            m = re.match(r"(CMAKE_BUILD_TYPE|CMAKE_CXX_COMPILER|CMAKE_CXX_FLAGS|CMAKE_CXX_FLAGS_RELEASE):\w+=(.*)",
                         line)
            if m:
                info[m.group(1)] = m.group(2)
        info["cache"] = str(cache.relative_to(REPO))
        break
    lists = REPO / "CMakeLists.txt"
    if lists.exists():
        m = re.search(r"target_compile_options\(_core PRIVATE([^)]*)\)", lists.read_text())
        if m:
            info["target_compile_options"] = " ".join(m.group(1).split())
    return info


def machine() -> dict[str, object]:
    cpu = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    return {"cpu": cpu, "cores": os.cpu_count(), "load_average_1_5_15": load, "platform": platform.platform(),
            "python": sys.version.split()[0]}


def provenance(level: str, argv: list[str] | None = None) -> dict[str, object]:
    from bsdflab import _core

    variant = None
    try:
        from bsdflab.reference.mitsuba_env import variant as mitsuba_variant

        variant = mitsuba_variant()
    except Exception:  # Mitsuba absent or unusable: the report says so
        variant = None
    dirty = _git("status", "--porcelain", "--untracked-files=no")
    return {
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "level": level,
        "command": " ".join(argv) if argv else None,
        "versions": {p: _version(p) for p in PACKAGES},
        "mitsuba_variant": variant,
        "git_commit": _git("rev-parse", "HEAD"),
        "git_dirty": bool(dirty) if dirty is not None else None,
        "core_build": core_build(),
        "core_threads": _core.worker_count(),
        "machine": machine(),
    }
