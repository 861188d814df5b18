#!/usr/bin/env bash
# Installs what is needed, builds with warnings as errors, and runs a tier of
# the tests (CTest, one test per GoogleTest suite; tests/CMakeLists.txt):
#
#   bash scripts/test.sh          the default tier (5-15 minutes from a fresh
#                                 clone on 2 cores, by the machine's speed):
#                                 the unit tests (invariants, fast paths against the shared
#                                 definitions, cache, post, globe) built with
#                                 AddressSanitizer and UndefinedBehaviorSanitizer,
#                                 but for three kinds that run in the release
#                                 build: those that compile shaders (GPU against
#                                 the CPU twins, plugin, the random sweep's
#                                 fixed-seed subset), those that run the CLI
#                                 and the example, and the few that take minutes
#                                 under the sanitizers (labels gpu, apps, slow);
#                                 with the release build also accuracy against
#                                 the stored reference results
#                                 (tests/data/reference/) and the installed
#                                 package. Each build compiles only the test
#                                 files it runs;
#   bash scripts/test.sh --full   the full tier (at most 45 minutes): everything
#                                 in the release build, a quarter of the
#                                 references recomputed and checked bit for bit
#                                 against the stored ones, Venus, the dense
#                                 atmospheres and the convergence of the orders;
#                                 in the sanitizer build the unit tests but for
#                                 the CLI's and the example's and the longest
#                                 GPU suites (see below).
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

# The release build (GCC): everything in the full tier; in the default tier
# what its tests need (the tests, and the CLI and libraries the package
# installs). The default tier's builds and the full tier's sanitizer build
# are unity builds (ATMOS_UNITY_BUILD, CMakeLists.txt): built from scratch,
# about a sixth less compile time. The full tier's release build recomputes
# stored references and checks them bit for bit, so it compiles the library
# file by file, as when they were stored.
if [ "$tier" = full ]; then
  bash "$root/scripts/build.sh" -DATMOS_WERROR=ON -DATMOS_TEST_FILES=all -DATMOS_UNITY_BUILD=OFF
else
  # Of the unit tests, only the files with a suite this build runs
  # (ATMOS_TEST_FILES, tests/CMakeLists.txt); the sanitizer build below
  # compiles the others.
  cmake -S "$root" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DATMOS_WERROR=ON \
    -DATMOS_TEST_FILES=release-tier -DATMOS_UNITY_BUILD=ON > /dev/null
  cmake --build "$root/build" --parallel "$jobs" --target atmos_tests atmos_accuracy_tests atmos_cli
fi
echo "test.sh: built in $(( $(date +%s) - start )) s; running the $tier tier"
main_labels=(-L "^$tier$")
if [ "$tier" = full ]; then
  export ATMOS_REFERENCE_MODE=verify
else
  # The unit tests run in the sanitizer build below, but for those that
  # compile shaders (tests/CMakeLists.txt, ATMOS_GPU_SUITES), run the CLI
  # and the example (ATMOS_APP_SUITES) or are slow under the sanitizers
  # (ATMOS_SLOW_UNIT_SUITES): the release build runs these.
  main_labels+=(-L '^(accuracy|package|gpu|apps|slow)$')
fi
status=0
ctest --test-dir "$root/build" --output-on-failure --parallel "$jobs" "${main_labels[@]}" \
  --output-junit "$report/main.xml" || status=$?
python3 "$root/scripts/slowest_tests.py" "$report/main.xml" --title "release build" || true
unset ATMOS_REFERENCE_MODE
[ "$status" -eq 0 ] || { echo "test.sh: the $tier tier failed" >&2; exit "$status"; }

# Sanitizers: the unit tests of the tier, built at -O1 (CMakeLists.txt) with
# clang, which compiles them in 40 % less time than GCC and runs them faster;
# so the code is also checked by a second compiler's warnings. This build has
# only the baseline x86-64 code of the precomputation's hot loops (no AVX2
# copy), so that with the release build both copies are tested.
sanitize="$root/build-sanitize"
# Figures for the generated docs (scripts/docs.sh) come from the release build.
unset ATMOS_FIGURES_FILE
test_files=sanitizer-tier
[ "$tier" = full ] && test_files=all
CC=clang CXX=clang++ cmake -S "$root" -B "$sanitize" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DATMOS_UNITY_BUILD=ON -DATMOS_SANITIZE=ON -DATMOS_WERROR=ON -DATMOS_KERNEL_CLONES=OFF -DATMOS_TEST_APPS=OFF \
  -DATMOS_TEST_FILES="$test_files" > /dev/null
cmake --build "$sanitize" --parallel "$jobs" --target atmos_tests
echo "test.sh: sanitizer build done at $(( $(date +%s) - start )) s"
sanitize_labels=(-L '^unit$' -L "^$tier$")
# The default tier leaves the slow and gpu suites to the release build. The
# full tier runs the slow ones here too and the GPU suites of the library's
# host code (the plugin, post-processing, stereo, eclipses, stars, the
# instant mode, the light maps, tile streaming), but leaves to the release
# build the suites of many minutes at -O1 whose code the sanitizers see in
# shorter suites, and the command-line tool and the example (their processes
# recompute tables and recompile programs; this build leaves them out,
# ATMOS_TEST_APPS=OFF):
#  - the GPU against the CPU twins (Gpu), the globe's and the sea's draws
#    (GlobeGpu, OceanGpu, OceanSpectralGpu, WaterGpu): their CPU code is the twins', the
#    globe's and the sea's, which other suites run here (Tables, Spectral,
#    SpectralSky..., Relief, GlobeMesh, GlobeLod, GlobeStreaming, WaterFresnel,
#    WaterGlint, WaterColumn...);
#  - the random sweep's 250 runs (SweepLong);
#  - the streamed descent onto Mars (GlobeStreamingMars; here the same
#    streaming on Earth, GlobeStreaming, and the Mars relief in the Relief
#    and GlobeMesh suites);
#  - the thick presets' tables (ThickPresets: Venus and Titan at default
#    sizes; here every preset at small sizes, Presets and PresetSky);
#  - the solved tail of the orders on thick atmospheres (ConvergenceTail;
#    here the same solver on Earth and a dense Earth, Convergence and
#    DenseEarth).
if [ "$tier" = full ]; then
  sanitize_labels+=(-E '^(Gpu|GlobeGpu|OceanGpu|OceanSpectralGpu|WaterGpu|SweepLong|GlobeStreamingMars|ThickPresets|ConvergenceTail)$')
else
  sanitize_labels+=(-LE '^(slow|gpu)$')
fi
status=0
ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir "$sanitize" --output-on-failure --parallel "$jobs" "${sanitize_labels[@]}" \
  --output-junit "$report/sanitize.xml" || status=$?
python3 "$root/scripts/slowest_tests.py" "$report/sanitize.xml" --title "sanitizer build" || true
[ "$status" -eq 0 ] || { echo "test.sh: the $tier tier failed in the sanitizer build" >&2; exit "$status"; }
echo "test.sh: the $tier tier passed in $(( $(date +%s) - start )) s (reports: $report)"
