#!/usr/bin/env bash
# Recomputes the stored results of the references (tests/data/reference/):
# runs every accuracy suite with ATMOS_REFERENCE_MODE=write, which computes
# each reference call the tests make and stores it under a hash of its inputs
# and of the reference's code. Needed after a change of the reference's code,
# of a test's reference inputs, or of a preset the accuracy tests read.
# Takes about as long as the full tier's accuracy tests (30-40 minutes on 2 cores).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${ATMOS_BUILD_DIR:-$root/build}"
bash "$root/scripts/build.sh"
rm -f "$root"/tests/data/reference/*.json
export ATMOS_CACHE_DIR="${ATMOS_CACHE_DIR:-$(mktemp -d)}"
ATMOS_REFERENCE_MODE=write ctest --test-dir "$build" --output-on-failure --parallel "$(nproc)" -L '^accuracy$'
echo "update-references: $(ls "$root"/tests/data/reference/*.json | wc -l) stores written to tests/data/reference/"
