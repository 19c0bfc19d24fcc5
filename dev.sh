#!/usr/bin/env bash
# One entry point for a fresh Debian machine (run as root, or with the system packages
# below already present):
#   ./dev.sh demo   set everything up, then run the main job
#   ./dev.sh test   set everything up, lint (ruff, clang-format, import layers), then run
#                   the test suite (what CI runs)
#   ./dev.sh setup  only set up (system packages, .venv, build of the C++ core)
#   ./dev.sh lint   only lint: ruff, clang-format, the import layers (after setup)
# Extra arguments after `test` go to pytest (e.g. ./dev.sh test -m slow).
set -euo pipefail
cd "$(dirname "$0")"

# libembree-dev: ray intersection for the renderer; libllvm19: Mitsuba's llvm_ad_* variants
# (the default LLVM 15 crashes them); python3-venv/-dev: a venv and headers on Debian's Python;
# chromium: the service page's real-browser test (driven by pip playwright, no browser download).
SYSTEM_PACKAGES=(build-essential python3-dev python3-venv libembree-dev libllvm19 chromium)
VENV=.venv
# Blender as a Python module for `bsdflab export --format blender` and its Cycles checks: its
# own venv, because bpy 5.0.1 pins numpy < 2 (bsdflab runs it in a child process).
BLENDER_VENV=.venv-blender
BPY_VERSION=5.0.1

install_system_packages() {
    command -v dpkg-query >/dev/null 2>&1 || { echo "dev.sh: not a Debian system; install ${SYSTEM_PACKAGES[*]} yourself" >&2; return 0; }
    local missing=()
    for p in "${SYSTEM_PACKAGES[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    if [ "$(id -u)" -ne 0 ]; then
        echo "dev.sh: missing system packages: ${missing[*]} (run as root or install them)" >&2
        exit 1
    fi
    echo "dev.sh: installing system packages: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

setup() {
    install_system_packages
    if [ ! -x "$VENV/bin/python" ]; then
        python3 -m venv "$VENV"
    fi
    "$VENV/bin/python" -m pip install -q --upgrade pip
    # Editable install: builds bsdflab._core (C++) and installs every dependency from
    # pyproject.toml, the test extras included.
    "$VENV/bin/python" -m pip install -q -e ".[test]"
    if [ ! -x "$BLENDER_VENV/bin/python" ]; then
        python3 -m venv "$BLENDER_VENV"
    fi
    "$BLENDER_VENV/bin/python" -m pip install -q "bpy==$BPY_VERSION"
}

# The layer contracts of pyproject.toml ([tool.importlinter]), checked by import-linter on
# the tree as the wheel lays it out: service/ and reference/ inside bsdflab/, where they
# ship as bsdflab.service and bsdflab.reference (wheel.packages). `python -S` keeps the
# editable install's import hook from pointing `bsdflab` back at the repository folder.
lint_imports() {
    local stage repo=$PWD site rc=0
    site=$("$VENV/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
    stage=$(mktemp -d)
    mkdir "$stage/bsdflab"
    cp -r bsdflab/. "$stage/bsdflab/"
    cp -r service "$stage/bsdflab/service"
    cp -r reference "$stage/bsdflab/reference"
    # the compiled core as a placeholder module, so `from bsdflab import _core` reads as an
    # import of bsdflab._core (below every layer), not of the package root
    : > "$stage/bsdflab/_core.py"
    (cd "$stage" && "$repo/$VENV/bin/python" -S -c '
import sys
sys.path[:0] = [".", sys.argv[2]]
from importlinter.cli import lint_imports_command
lint_imports_command.main([sys.argv[1], "--no-cache"], prog_name="lint-imports")
' "$repo/pyproject.toml" "$site") || rc=$?
    rm -rf "$stage"
    return $rc
}

# Lint, format and layer checks (configs: [tool.ruff] and [tool.importlinter] in pyproject.toml,
# .clang-format): fail
# before the tests run. `ruff check --fix .` and `clang-format -i` fix most findings.
lint() {
    "$VENV/bin/ruff" check .
    find core \( -name '*.h' -o -name '*.cpp' \) -print0 | xargs -0 "$VENV/bin/clang-format" --dry-run --Werror
    lint_imports
}

cmd=${1:-demo}
shift || true
case "$cmd" in
    setup) setup ;;
    lint) lint ;;
    demo)
        setup
        mkdir -p out
        # Tabulates the snake's layered BSDF on first use (cached), then renders it.
        "$VENV/bin/bsdflab" render snake --width 1280 --height 720 --spp 256 --out out/snake.exr "$@"
        ;;
    test)
        setup
        lint
        # one worker per core (at most 4: each can hold ~1.5 GB), whole files per worker,
        # longest files first (tests/support/scheduling.py)
        "$VENV/bin/python" -m pytest -m "not slow" -n auto --maxprocesses 4 --dist loadfile \
            --no-loadscope-reorder "$@"
        ;;
    *) echo "usage: ./dev.sh [demo|test|setup|lint] [args...]" >&2; exit 2 ;;
esac
