#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ with clang, AddressSanitizer and
# UndefinedBehaviorSanitizer, and runs each on a copy of its seed corpus
# (tests/data/fuzz/<target>/) for N executions. Not part of the tests or CI.
#
#   bash scripts/fuzz.sh [--runs N] [planet|cache]...
#
#   planet  atmos::parse_atmosphere on arbitrary bytes (fuzz/planet_file_fuzzer.cpp)
#   cache   the table cache file's decoder (fuzz/cache_file_fuzzer.cpp)
#   --runs  executions per target (default 1000000)
#
# Environment: ATMOS_FUZZ_BUILD_DIR (default build-libfuzzer/), ATMOS_FUZZ_TIMEOUT
# (seconds one input may take, default 10), ATMOS_FUZZ_RSS_MB (default 2048),
# ATMOS_FUZZ_MALLOC_MB (the largest single allocation, default 256).
# Each target works in $ATMOS_FUZZ_BUILD_DIR/work/<target>/: corpus/ (the copy,
# grown by the run), findings/ (an input that crashed, hung or ran out of
# memory) and log. The exit status is 1 if any target had a finding.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${ATMOS_FUZZ_BUILD_DIR:-$root/build-libfuzzer}"
timeout="${ATMOS_FUZZ_TIMEOUT:-10}"
rss_mb="${ATMOS_FUZZ_RSS_MB:-2048}"
malloc_mb="${ATMOS_FUZZ_MALLOC_MB:-256}"
runs=1000000
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs="${2:?--runs needs a number}"; shift 2 ;;
    --runs=*) runs="${1#--runs=}"; shift ;;
    planet|cache) targets+=("$1"); shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "fuzz.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
if ! [[ "$runs" =~ ^[1-9][0-9]*$ ]]; then
  echo "fuzz.sh: --runs needs a positive number, got '$runs'" >&2
  exit 2
fi
[ ${#targets[@]} -gt 0 ] || targets=(planet cache)

bash "$root/scripts/setup.sh"

# Assertions stay on (no -DNDEBUG); line tables make the sanitizers' stacks readable.
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Fuzz \
  -DCMAKE_CXX_FLAGS="-O2 -gline-tables-only" -DATMOS_FUZZ=ON -DATMOS_BUILD_TESTS=OFF -DATMOS_BUILD_APPS=OFF \
  -DATMOS_KERNEL_CLONES=OFF > /dev/null
cmake --build "$build" --parallel "$(nproc)" --target planet_file_fuzzer cache_file_fuzzer cache_seed_writer

export ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=1:detect_stack_use_after_return=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

summary=()
status=0
for target in "${targets[@]}"; do
  work="$build/work/$target"
  rm -rf "$work"
  mkdir -p "$work/findings"
  cp -r "$root/tests/data/fuzz/$target" "$work/corpus"
  extra=()
  case "$target" in
    planet)
      exe="$build/fuzz/planet_file_fuzzer"
      extra+=(-dict="$root/tests/data/fuzz/planet.dict")
      ;;
    cache)
      exe="$build/fuzz/cache_file_fuzzer"
      # Real files of the current format and physics next to the stored seeds
      # (whose key and version go stale when either changes).
      ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" "$build/fuzz/cache_seed_writer" "$work/corpus/current"
      ;;
  esac
  echo "fuzz: $target, $runs executions (log: $work/log)"
  set +e
  "$exe" "$work/corpus" -runs="$runs" -timeout="$timeout" -rss_limit_mb="$rss_mb" -malloc_limit_mb="$malloc_mb" \
    -artifact_prefix="$work/findings/" -print_final_stats=1 "${extra[@]}" > "$work/log" 2>&1
  code=$?
  set -e
  executed=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/log" | tail -1)
  per_second=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$work/log" | tail -1)
  coverage=$(grep -E '^#[0-9]+' "$work/log" | tail -1 | grep -oE 'cov: [0-9]+ ft: [0-9]+' || true)
  findings=$(find "$work/findings" -type f | sort)
  if [ "$code" -eq 0 ] && [ -z "$findings" ]; then
    result="no finding"
  else
    result="FINDING (libFuzzer exit $code): ${findings:-see the log}"
    status=1
  fi
  summary+=("$(printf '%-7s %10s executions, %6s exec/s, %s: %s' "$target" "${executed:-?}" "${per_second:-?}" \
    "${coverage:-cov ?}" "$result")")
done

echo
echo "fuzz: results"
printf '  %s\n' "${summary[@]}"
exit "$status"
