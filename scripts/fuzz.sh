#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, docs/fuzzing.md) in ${FUZZ_BUILD_DIR:-build-fuzz} with
# clang-14 and runs them on a copy of the seed corpora kept in that build directory.
#   scripts/fuzz.sh [TARGET|all] [SECONDS]   one target or all, SECONDS each (default 60)
#   scripts/fuzz.sh --ci                      every target for 20 s, two at a time
#   scripts/fuzz.sh --coverage [TARGET|all]   replays the corpora of the runs above in a build
#                                             with source-based coverage (${FUZZ_BUILD_DIR}-cov)
#                                             and prints the line coverage of the reader sources
# Prints per target the executions, libFuzzer's final cov:/ft: and any crash/leak/timeout/oom
# file; exits non-zero when a target found something.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
build_dir=${FUZZ_BUILD_DIR:-build-fuzz}
mode=fuzz
if [[ ${1:-} == --coverage ]]; then
  mode=coverage
  shift
fi
target=${1:-all}
seconds=${2:-60}
parallel=${FUZZ_PARALLEL:-1}
if [[ $target == --ci ]]; then
  # CI: two targets at a time (the 2 cores of the CI machine), 20 s each.
  target=all
  seconds=20
  parallel=${FUZZ_PARALLEL:-2}
fi
run_dir=$build_dir/fuzz-run
[[ $mode == coverage ]] && build_dir=$build_dir-cov

export CC=${CC:-clang-14} CXX=${CXX:-clang++-14}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSGDICP_FUZZ=ON \
  -DSGDICP_FUZZ_COVERAGE=$([[ $mode == coverage ]] && echo ON || echo OFF) \
  -DSGDICP_BUILD_TESTS=OFF -DSGDICP_BUILD_APPS=OFF -DSGDICP_WARNINGS_AS_ERRORS=ON >/dev/null
list="$build_dir/fuzz/fuzz_targets.txt"
if [[ $target == all ]]; then
  targets=$(cut -d' ' -f1 "$list")
else
  if ! grep -q "^$target " "$list"; then
    echo "unknown target '$target'; known: $(cut -d' ' -f1 "$list" | xargs)" >&2
    exit 2
  fi
  targets=$target
fi
# shellcheck disable=SC2086
cmake --build "$build_dir" -j2 --target $targets >/dev/null

if [[ $mode == coverage ]]; then
  profiles=()
  for name in $targets; do
    corpus="$run_dir/$name/corpus"
    [[ -d $corpus ]] || corpus="fuzz/corpus/$name"
    LLVM_PROFILE_FILE="$build_dir/$name.profraw" "$build_dir/fuzz/$name" -runs=0 "$corpus" \
      >"$build_dir/$name.replay.txt" 2>&1
    profiles+=("$build_dir/$name.profraw")
    echo "$name: replayed $(find "$corpus" -type f | wc -l) inputs of $corpus"
  done
  llvm-profdata-14 merge -sparse "${profiles[@]}" -o "$build_dir/fuzz.profdata"
  objects=()
  for name in $targets; do objects+=(-object "$build_dir/fuzz/$name"); done
  llvm-cov-14 report "${objects[@]:1}" -instr-profile="$build_dir/fuzz.profdata" \
    src/io/*.cpp src/io/depth_image.cpp src/io/parse_number.cpp src/io/transform_io.cpp src/tools/pairs.cpp
  exit 0
fi

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# Runs one target; writes its summary line to $work/summary.txt and returns 1 on a finding.
run_target() {
  local name=$1 work="$run_dir/$1" max_len dict_file rc=0 execs last cov ft findings
  max_len=$(awk -v n="$name" '$1 == n { print $2 }' "$list")
  dict_file=$(awk -v n="$name" '$1 == n { print $3 }' "$list")
  mkdir -p "$work/corpus" "$work/artifacts"
  rm -f "$work/summary.txt"
  cp -n "fuzz/corpus/$name"/* "$work/corpus/" 2>/dev/null || true
  find "$work/artifacts" -type f -printf '%f\n' | sort >"$work/before.txt"
  "$build_dir/fuzz/$name" -dict="$root/fuzz/dict/$dict_file" -max_len="$max_len" -timeout=10 \
    -rss_limit_mb=2048 -max_total_time="$seconds" -print_final_stats=1 \
    -artifact_prefix="$work/artifacts/" "$work/corpus" >"$work/log.txt" 2>&1 || rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/log.txt" | tail -1)
  last=$(grep -E '^#[0-9]+.* cov: ' "$work/log.txt" | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  findings=$(find "$work/artifacts" -type f -printf '%f\n' | sort | comm -13 "$work/before.txt" - |
    grep -E '^(crash|leak|timeout|oom)-' | sed "s|^|$work/artifacts/|" | xargs || true)
  [[ $rc -ne 0 ]] && findings="${findings:-exit $rc} (log: $work/log.txt)"
  printf '%-16s %8s %12s %7s %7s  %s\n' "$name" "$seconds" "${execs:-?}" "${cov:-?}" "${ft:-?}" \
    "${findings:-none}" >"$work/summary.txt"
  return $((rc != 0))
}

for name in $targets; do
  while (($(jobs -rp | wc -l) >= parallel)); do wait -n || true; done
  run_target "$name" &
done
wait
status=0
printf '%-16s %8s %12s %7s %7s  %s\n' target seconds execs cov ft findings
for name in $targets; do
  cat "$run_dir/$name/summary.txt"
  grep -q ' none$' "$run_dir/$name/summary.txt" || status=1
done
exit $status
