#!/usr/bin/env bash
# One command for a fresh Debian 12 machine: install dependencies, build, and register the
# bundled demo pair (libpointmatcher car scans), printing the transform and its errors against
# the ground truth and writing a picture of the alignment to demo.png.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh sgdicp_cli  # the CLI only: the demo needs no test binary
build_dir=${BUILD_DIR:-build}
"$build_dir/sgdicp" register data/demo/car_cloud401.csv data/demo/car_cloud400.csv \
  --ground-truth data/demo/T_gt.txt --picture demo.png "$@"
