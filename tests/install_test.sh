#!/usr/bin/env bash
# Installs the built project into a temporary prefix, then configures, builds and runs a small
# consumer project that uses find_package(sgdicp).
set -euo pipefail
build_dir=$1
source_dir=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build_dir" --prefix "$tmp/prefix" >/dev/null
# The installed package must not name files of this machine (liblzf is linked by name).
if grep -n "$build_dir\|/usr/lib[^ ]*liblzf" "$tmp"/prefix/lib*/cmake/sgdicp/*.cmake; then
  echo "install_test: the installed CMake files name absolute paths of the build machine" >&2
  exit 1
fi
test -f "$tmp/prefix/include/sgdicp/version.hpp"
cmake -S "$source_dir/tests/consumer" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" >/dev/null
cmake --build "$tmp/build" >/dev/null
"$tmp/build/consumer"
