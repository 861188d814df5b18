#!/usr/bin/env bash
# Install what is needed, build, and run the whole test suite (CTest +
# GoogleTest), then the fast tests again under AddressSanitizer and
# UndefinedBehaviorSanitizer. OpenGL runs headless (EGL, Mesa llvmpipe on
# machines without a GPU).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
export ATMOS_CACHE_DIR="${ATMOS_CACHE_DIR:-$(mktemp -d)}"

bash "$root/scripts/build.sh" -DATMOS_WERROR=ON
ctest --test-dir "$root/build" --output-on-failure --parallel 1 --timeout 1200

# Sanitizers: everything except the long accuracy runs. This build has only
# the baseline x86-64 code of the precomputation's hot loops (no AVX2 copy),
# so that both copies are tested.
ATMOS_BUILD_DIR="$root/build-sanitize" bash "$root/scripts/build.sh" -DATMOS_SANITIZE=ON -DATMOS_WERROR=ON \
  -DATMOS_KERNEL_CLONES=OFF
ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir "$root/build-sanitize" --output-on-failure --parallel 1 --timeout 1200 -LE slow
