#!/usr/bin/env bash
# Regenerates the measured documents (docs/accuracy.md, docs/performance.md,
# docs/instant.md and README.md's headline figures) from a run: builds if
# needed, runs the tests whose figures the templates in docs/templates/ quote (with
# ATMOS_FIGURES_FILE set: tests/figures.hpp) and `atmos bench`, then
# scripts/docs.py. The run's raw output stays in <build>/docs-run/.
#
#   bash scripts/docs.sh                      # the whole run
#   bash scripts/docs.sh --figures F --bench B  # reuse an earlier run's output
#   bash scripts/docs.sh -- --allow-missing   # arguments after -- go to docs.py
#
# The build directory is $ATMOS_BUILD_DIR (default build/); tables are cached
# in $ATMOS_CACHE_DIR (default: a fresh temporary directory, so that the
# precomputation is measured, not read back). The test run takes as long as
# the tests it runs (the bench a few minutes more); both times are printed
# and written into the documents.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${ATMOS_BUILD_DIR:-$root/build}"
figures="" bench=""
docs_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --figures) figures="$2"; shift 2 ;;
    --bench) bench="$2"; shift 2 ;;
    --) shift; docs_args=("$@"); break ;;
    *) echo "docs.sh: unknown argument $1 (see the comment at the top of scripts/docs.sh)" >&2; exit 2 ;;
  esac
done

run="$build/docs-run"
meta=()
# The commit the run measures (what is built from the working tree).
commit="$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
if [ -n "$(git -C "$root" status --porcelain --untracked-files=no 2>/dev/null)" ]; then
  commit="$commit with uncommitted changes"
fi
if [ -z "$figures" ] || [ -z "$bench" ]; then
  # Every test file: the figures' tests are in the release build's and in
  # the sanitizer build's files alike (a build/ left by scripts/test.sh's
  # default tier has only the former).
  ATMOS_BUILD_DIR="$build" bash "$root/scripts/build.sh" -DATMOS_TEST_FILES=all
  mkdir -p "$run"
  export ATMOS_CACHE_DIR="${ATMOS_CACHE_DIR:-$(mktemp -d)}"
fi

if [ -z "$figures" ]; then
  figures="$run/figures.jsonl"
  : > "$figures"
  : > "$run/tests.log"
  filter="$(python3 "$root/scripts/docs.py" --list-tests)"
  echo "docs.sh: running the tests that carry figures: $filter"
  start=$(date +%s)
  failed=0
  found=0
  while IFS= read -r binary; do
    found=1
    echo "docs.sh: $binary"
    ATMOS_FIGURES_FILE="$figures" "$binary" --gtest_filter="$filter" >> "$run/tests.log" 2>&1 || failed=1
  done < <(find "$build" -path "$build/docs-run" -prune -o -type f -executable -name 'atmos_*tests' -print | sort)
  [ "$found" = 1 ] || { echo "docs.sh: no test executables (atmos_*tests) in $build" >&2; exit 1; }
  seconds=$(( $(date +%s) - start ))
  echo "docs.sh: tests took $((seconds / 60)) min $((seconds % 60)) s ($(wc -l < "$figures") figures; log: $run/tests.log)"
  printf 'tests_time=%s\ntest_filter=%s\ntests_commit=%s\n' "$((seconds / 60)) min $((seconds % 60)) s" "$filter" \
    "$commit" > "$figures.meta"
  if [ "$failed" = 1 ]; then
    echo "docs.sh: some tests failed (see $run/tests.log); the documents are not written" >&2
    exit 1
  fi
fi

if [ -z "$bench" ]; then
  bench="$run/bench.tsv"
  cli=""
  for candidate in "$build/atmos" "$build/apps/atmos/atmos" "$build/apps/atmos"; do
    if [ -f "$candidate" ] && [ -x "$candidate" ]; then cli="$candidate"; break; fi
  done
  [ -n "$cli" ] || cli="$(find "$build" -type f -executable -name atmos | head -n 1)"
  [ -n "$cli" ] || { echo "docs.sh: no atmos executable in $build" >&2; exit 1; }
  echo "docs.sh: $cli bench"
  start=$(date +%s)
  load_before="$(cut -d' ' -f1 /proc/loadavg)"
  "$cli" bench > "$bench"
  seconds=$(( $(date +%s) - start ))
  echo "docs.sh: bench took $((seconds / 60)) min $((seconds % 60)) s"
  printf 'bench_time=%s\nbench_load=%s\nbench_commit=%s\n' "$((seconds / 60)) min $((seconds % 60)) s" \
    "$load_before before, $(cut -d' ' -f1 /proc/loadavg) after" "$commit" > "$bench.meta"
fi

# Facts about the run, kept next to its output (also when it is reused).
for file in "$figures.meta" "$bench.meta"; do
  if [ -f "$file" ]; then
    while IFS= read -r line; do meta+=(--meta "$line"); done < "$file"
  fi
done

python3 "$root/scripts/docs.py" --figures "$figures" --bench "$bench" "${meta[@]}" "${docs_args[@]}"
