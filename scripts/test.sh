#!/usr/bin/env bash
# Installs what is needed, builds with warnings as errors, and runs a tier of
# the tests (CTest, one test per GoogleTest suite; tests/CMakeLists.txt):
#
#   bash scripts/test.sh          the default tier (15-18 minutes from a
#                                 fresh clone on 2 cores): the unit tests
#                                 (invariants, fast paths against the shared
#                                 definitions, cache, post, plugin, globe, GPU
#                                 against the CPU twins, the random sweep's
#                                 fixed-seed subset), built with AddressSanitizer
#                                 and UndefinedBehaviorSanitizer; with the
#                                 release build, accuracy against the stored
#                                 reference results (tests/data/reference/), the
#                                 installed package, the unit tests that compile
#                                 shaders, those that run the CLI and the
#                                 example, and the few that take minutes under
#                                 the sanitizers (label slow), which this tier
#                                 leaves out of the sanitizer build;
#   bash scripts/test.sh --full   the full tier (at most 45 minutes): everything,
#                                 the unit tests in both builds, the references
#                                 recomputed and checked bit for bit against the
#                                 stored ones, Venus, the dense atmospheres and
#                                 the convergence of the orders.
#
# Each run prints the 10 slowest tests of each build. OpenGL runs headless
# (EGL; Mesa llvmpipe on machines without a GPU).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tier=default
case "${1:-}" in
  "") ;;
  --full) tier=full ;;
  *) echo "usage: bash scripts/test.sh [--full]" >&2; exit 2 ;;
esac
jobs="$(nproc)"
start=$(date +%s)
bash "$root/scripts/setup.sh"
export ATMOS_CACHE_DIR="${ATMOS_CACHE_DIR:-$(mktemp -d)}"
report="$(mktemp -d)"

# The release build: everything in the full tier; in the default tier what
# its tests need (the tests, and the CLI and libraries the package installs).
if [ "$tier" = full ]; then
  bash "$root/scripts/build.sh" -DATMOS_WERROR=ON
else
  cmake -S "$root" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DATMOS_WERROR=ON > /dev/null
  cmake --build "$root/build" --parallel "$jobs" --target atmos_tests atmos_accuracy_tests atmos_cli
fi
echo "test.sh: built in $(( $(date +%s) - start )) s; running the $tier tier"
main_labels=(-L "^$tier$")
if [ "$tier" = full ]; then
  export ATMOS_REFERENCE_MODE=verify
else
  # The unit tests run in the sanitizer build below; of them, the release
  # build runs those that compile shaders, filling Mesa's shader cache
  # (tests/CMakeLists.txt, ATMOS_GPU_SUITES), and those that run the CLI and
  # the example, which the sanitizer build of this tier leaves out
  # (ATMOS_APP_SUITES), and the unit suites slow under the sanitizers
  # (ATMOS_SLOW_UNIT_SUITES), which it leaves out too.
  main_labels+=(-L '^(accuracy|package|gpu|apps|slow)$')
fi
status=0
ctest --test-dir "$root/build" --output-on-failure --parallel "$jobs" "${main_labels[@]}" \
  --output-junit "$report/main.xml" || status=$?
python3 "$root/scripts/slowest_tests.py" "$report/main.xml" --title "release build" || true
unset ATMOS_REFERENCE_MODE
[ "$status" -eq 0 ] || { echo "test.sh: the $tier tier failed" >&2; exit "$status"; }

# Sanitizers: the unit tests of the tier, built at -O1 (CMakeLists.txt). This
# build has only the baseline x86-64 code of the precomputation's hot loops
# (no AVX2 copy), so that with the release build both copies are tested.
sanitize="$root/build-sanitize"
# Figures for the generated docs (scripts/docs.sh) come from the release build.
unset ATMOS_FIGURES_FILE
test_apps=OFF
[ "$tier" = full ] && test_apps=ON
cmake -S "$root" -B "$sanitize" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DATMOS_SANITIZE=ON -DATMOS_WERROR=ON -DATMOS_KERNEL_CLONES=OFF -DATMOS_TEST_APPS="$test_apps" > /dev/null
cmake --build "$sanitize" --parallel "$jobs" --target atmos_tests
echo "test.sh: sanitizer build done at $(( $(date +%s) - start )) s"
sanitize_labels=(-L '^unit$' -L "^$tier$")
# The default tier leaves the slow suites to the release build; the full
# tier runs them here too, but leaves to the release build the sweep's
# 500-run subset (SweepLong, minutes of shader variants; the sanitizers still
# see the 60-run subset) and the streamed descent onto Mars
# (GlobeStreamingMars, minutes of the Mars style's relief at -O1; the
# sanitizers see the same streaming on Earth, GlobeStreaming, and the Mars
# relief in the Relief and GlobeMesh suites).
if [ "$tier" = full ]; then
  sanitize_labels+=(-E '^(SweepLong|GlobeStreamingMars)$')
else
  sanitize_labels+=(-LE '^slow$')
fi
status=0
ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir "$sanitize" --output-on-failure --parallel "$jobs" "${sanitize_labels[@]}" \
  --output-junit "$report/sanitize.xml" || status=$?
python3 "$root/scripts/slowest_tests.py" "$report/sanitize.xml" --title "sanitizer build" || true
[ "$status" -eq 0 ] || { echo "test.sh: the $tier tier failed in the sanitizer build" >&2; exit "$status"; }
echo "test.sh: the $tier tier passed in $(( $(date +%s) - start )) s (reports: $report)"
