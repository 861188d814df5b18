#!/usr/bin/env bash
# Configures and builds atmos into build/ (or $ATMOS_BUILD_DIR).
# Extra arguments are passed to CMake, e.g. -DATMOS_SANITIZE=ON.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${ATMOS_BUILD_DIR:-$root/build}"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" > /dev/null
cmake --build "$build" --parallel "$(nproc)"
