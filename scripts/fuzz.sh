#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, docs/fuzzing.md) in ${FUZZ_BUILD_DIR:-build-fuzz} with
# clang-14 and runs them on a copy of the seed corpora kept in that build directory.
#   scripts/fuzz.sh [TARGET|all] [SECONDS]   one target or all, SECONDS each (default 60)
#   scripts/fuzz.sh --ci                      every target for 20 s
# Prints per target the executions, libFuzzer's final cov:/ft: and any crash/leak/timeout/oom
# file; exits non-zero when a target found something.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
build_dir=${FUZZ_BUILD_DIR:-build-fuzz}
target=${1:-all}
seconds=${2:-60}
if [[ $target == --ci ]]; then
  target=all
  seconds=20
fi

export CC=${CC:-clang-14} CXX=${CXX:-clang++-14}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSGDICP_FUZZ=ON \
  -DSGDICP_BUILD_TESTS=OFF -DSGDICP_BUILD_APPS=OFF -DSGDICP_WARNINGS_AS_ERRORS=ON >/dev/null
list="$build_dir/fuzz/fuzz_targets.txt"
if [[ $target == all ]]; then
  targets=$(cut -d' ' -f1 "$list")
else
  grep -q "^$target " "$list" || { echo "unknown target '$target'; known: $(cut -d' ' -f1 "$list" | xargs)" >&2; exit 2; }
  targets=$target
fi
# shellcheck disable=SC2086
cmake --build "$build_dir" -j2 --target $targets >/dev/null

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
printf '%-16s %8s %12s %7s %7s  %s\n' target seconds execs cov ft findings
for name in $targets; do
  max_len=$(awk -v n="$name" '$1 == n { print $2 }' "$list")
  work="$build_dir/fuzz-run/$name"
  mkdir -p "$work/corpus" "$work/artifacts"
  cp -n "fuzz/corpus/$name"/* "$work/corpus/" 2>/dev/null || true
  dict_file=$(awk -v n="$name" '$1 == n { print $3 }' "$list")
  dict=()
  [[ -n $dict_file ]] && dict=("-dict=$root/fuzz/dict/$dict_file")
  find "$work/artifacts" -type f -printf '%f\n' | sort >"$work/before.txt"
  rc=0
  "$build_dir/fuzz/$name" "${dict[@]}" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 \
    -max_total_time="$seconds" -print_final_stats=1 -artifact_prefix="$work/artifacts/" \
    "$work/corpus" >"$work/log.txt" 2>&1 || rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/log.txt" | tail -1)
  last=$(grep -E '^#[0-9]+.* cov: ' "$work/log.txt" | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  findings=$(find "$work/artifacts" -type f -printf '%f\n' | sort | comm -13 "$work/before.txt" - |
    grep -E '^(crash|leak|timeout|oom)-' | sed "s|^|$work/artifacts/|" | xargs || true)
  if [[ $rc -ne 0 ]]; then
    status=1
    findings="${findings:-exit $rc} (log: $work/log.txt)"
  fi
  printf '%-16s %8s %12s %7s %7s  %s\n' "$name" "$seconds" "${execs:-?}" "${cov:-?}" "${ft:-?}" \
    "${findings:-none}"
done
exit $status
