#!/usr/bin/env bash
# One command for a fresh Debian 12 machine: install dependencies, build with warnings as errors,
# and run every test (unit, real-data and CLI tests through CTest). Real-data tests read
# ../shared/data beside the repository and skip when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
build_dir=${BUILD_DIR:-build}
ctest --test-dir "$build_dir" --output-on-failure -j"$(nproc)"
