#!/usr/bin/env bash
# Sanitizer runs of the C++ code: scripts/sanitize.sh [asan|asan-ci|tsan|all] (default all).
#   asan: every C++ test of ctest (unit, real-data and CLI tests) built with AddressSanitizer and
#         UndefinedBehaviorSanitizer in build-asan: leaks detected, the first error of either is
#         fatal. Only install_and_find_package is left out: it builds a consumer without the
#         sanitizer flags, which tests packaging, not memory.
#   tsan: the multi-threaded code built with ThreadSanitizer in build-tsan, and only that (a
#         TSan build of everything would double the stage for tests that start no thread):
#         8 threads on one ReferenceIndex (test_stress Load.*), concurrent KD-tree queries,
#         concurrent registrations on a shared index, normals and covariances on 1-4 threads
#         (the only std::jthread pool of the library), the voxel passes' block cache and block
#         sweep on two threads, and `sgdicp bench --jobs 2`.
# Both use RelWithDebInfo at -O1 (sanitized -O0 ran the suite several times slower; -O1 keeps
# the stacks readable) with -g1: line tables and function names, all a sanitizer's stack needs
# (a sanitized registration.cpp compiled in 75 s with -g1 against 400 s with -g on a loaded
# 2-core machine). The load and soak tests run a fifth and a tenth of their work when
# sanitized (tests/test_stress.cpp). Builds use ${SANITIZE_JOBS:-2} jobs.
# Measured under ASan+UBSan (shared 2-vCPU machine, load average 11-15): test_io 11 s,
# cli_tests 79 s (8 s unsanitized); the builds took far longer there than they will on an idle
# runner, so the stage durations printed by `stage` are the figures to keep CI within budget.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-all}
jobs=${SANITIZE_JOBS:-2}

configure() {  # configure DIR FLAGS
  cmake -S . -B "$1" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
    -DCMAKE_CXX_FLAGS="$2 -fno-omit-frame-pointer" -DCMAKE_EXE_LINKER_FLAGS="$2" \
    -DCMAKE_SHARED_LINKER_FLAGS="$2" -DSGDICP_WARNINGS_AS_ERRORS=ON -DSGDICP_BUILD_PYTHON=OFF \
    -DSGDICP_BUILD_BENCHMARKS=OFF >/dev/null
}

stage() {  # stage NAME COMMAND...: runs it and prints its duration
  local start=$SECONDS
  "${@:2}"
  echo "sanitize: $1 took $((SECONDS - start)) s"
}

run_asan() {
  configure build-asan "-fsanitize=address,undefined -fno-sanitize-recover=undefined"
  stage "asan build" cmake --build build-asan -j"$jobs"
  export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  stage "asan tests" ctest --test-dir build-asan --output-on-failure -j"$jobs" \
    -E '^install_and_find_package$'
}

# The CI subset (scripts/sanitize.sh asan-ci): the readers (every format, hostile files), the
# pose, scaling, sampler and gradient code, the convergence test and optimisers, non-finite input
# and the load/soak tests: the code that handles untrusted bytes and memory, in a build of a
# fraction of the suite (test_methods, test_registration and the CLI tests, ~6 of the ~10 sanitized
# minutes, run in the full `asan` mode).
ASAN_CI_TARGETS=(test_io test_core test_solver_parts test_nonfinite test_stress test_settings)

run_asan_ci() {
  configure build-asan "-fsanitize=address,undefined -fno-sanitize-recover=undefined"
  stage "asan build (ci subset)" cmake --build build-asan -j"$jobs" --target "${ASAN_CI_TARGETS[@]}"
  export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  for target in "${ASAN_CI_TARGETS[@]}"; do
    stage "asan $target" "build-asan/tests/$target" --gtest_brief=1
  done
}

TSAN_TARGETS=(test_stress test_core test_registration test_solver_parts test_preprocessing sgdicp_cli)
TSAN_TESTS='^(Load\.|HelperThread\.|WakeCounter\.|RecyclingAllocator\.|VoxelSurfaces\.EveryBlock|Threads\.|NearestNeighborTest\.Concurrent|ReferenceReuse\.|Covariances\.IdenticalForAnyThreadCount|VoxelDownsample\.HalvesMerge|RegistrationVoxelGrid\.TreeAlongside)'

tsan_bench() {  # the demo pair, twice per method, on two threads
  local pairs=build-tsan/demo_pairs.txt
  { printf '%s %s ' "$PWD/data/demo/car_cloud401.csv" "$PWD/data/demo/car_cloud400.csv"
    head -n 3 data/demo/T_gt.txt | tr '\n' ' '
    echo; } >"$pairs"
  build-tsan/sgdicp bench "$pairs" --method sgd,icp,gicp --repeat 2 --jobs 2 >/dev/null
  # One registration on two threads (voxel passes in halves, KD-tree, block surfaces) on clouds
  # large enough to be split: the Kinect frames of ../shared/data when present.
  local kinect=../shared/data/pairs/pcl_kinect_frames.txt
  if [ -f "$kinect" ]; then build-tsan/sgdicp bench "$kinect" --threads 2 >/dev/null; fi
}

run_tsan() {
  configure build-tsan "-fsanitize=thread"
  stage "tsan build" cmake --build build-tsan -j"$jobs" --target "${TSAN_TARGETS[@]}"
  export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
  stage "tsan tests" ctest --test-dir build-tsan --output-on-failure -j"$jobs" -R "$TSAN_TESTS"
  stage "tsan bench --jobs 2" tsan_bench
}

case "$mode" in
  asan) run_asan ;;
  asan-ci) run_asan_ci ;;
  tsan) run_tsan ;;
  all) run_asan && run_tsan ;;
  *) echo "usage: scripts/sanitize.sh [asan|asan-ci|tsan|all]" >&2; exit 2 ;;
esac
