#!/usr/bin/env bash
# Configures and builds sgd-icp (Release, warnings as errors) into ${BUILD_DIR:-build}.
#   scripts/build.sh [TARGET...]    only these targets (default: all, with every test binary)
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${BUILD_DIR:-build}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSGDICP_WARNINGS_AS_ERRORS=ON >/dev/null
targets=()
for t in "$@"; do targets+=(--target "$t"); done
cmake --build "$build_dir" -j"$(nproc)" "${targets[@]}"
