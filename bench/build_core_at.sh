#!/usr/bin/env bash
# Build the C++ core as it was at a commit, for bench/bench_layered_compare.py --baseline-core
# (today's PFMC when the working tree changes the core's speed):
#   bench/build_core_at.sh <commit> <out.so>
# Needs cmake, ninja and pybind11 for the venv's Python (`.venv/bin/pip install cmake ninja pybind11`)
# and the system packages of ./dev.sh setup (Embree).
set -euo pipefail
commit=$1 out=$2
repo=$(cd "$(dirname "$0")/.." && pwd)
py=$repo/.venv/bin/python
tmp=$(mktemp -d)
trap 'git -C "$repo" worktree remove --force "$tmp/src" >/dev/null 2>&1 || true; rm -rf "$tmp"' EXIT
git -C "$repo" worktree add --detach "$tmp/src" "$commit" >/dev/null
cmake -S "$tmp/src" -B "$tmp/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DPython_EXECUTABLE="$py" -Dpybind11_DIR="$("$py" -m pybind11 --cmakedir)" >/dev/null
cmake --build "$tmp/build" >/dev/null
cp "$tmp"/build/_core*.so "$out"
echo "built the core of $(git -C "$repo" rev-parse --short "$commit") into $out"
