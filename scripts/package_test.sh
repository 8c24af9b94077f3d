#!/usr/bin/env bash
# The Python packages as a user gets them: `python -m build` makes the sdist, then the wheel from
# that sdist (so a file missing from the sdist fails here), the wheel is installed into a fresh
# venv with the [test] extra, and the Python tests run against that installed copy (not the
# source tree). Needs network access to PyPI for the build requirements and the venv's packages.
#   scripts/package_test.sh [OUT_DIR]     (default: build-package; the sdist and wheel stay there)
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
out=${1:-build-package}
case "$out" in /*) ;; *) out="$repo/$out" ;; esac
rm -rf "$out"
mkdir -p "$out"
start=$(date +%s)

python3 -m venv "$out/build-venv"
"$out/build-venv/bin/pip" install --quiet --disable-pip-version-check build
settings=(-C cmake.define.SGDICP_WARNINGS_AS_ERRORS=ON)
if command -v ccache >/dev/null 2>&1; then
  settings+=(-C cmake.define.CMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
echo "package_test: python -m build (sdist, then the wheel from it)"
"$out/build-venv/bin/python" -m build --outdir "$out/dist" "${settings[@]}" .
sdist=$(ls "$out"/dist/*.tar.gz)
wheel=$(ls "$out"/dist/*.whl)
echo "package_test: built $(basename "$sdist") and $(basename "$wheel") in $(($(date +%s) - start)) s"

python3 -m venv "$out/venv"
"$out/venv/bin/pip" install --quiet --disable-pip-version-check "$wheel[test]"
# The installed package, not python/ of this checkout, must be the one imported.
location=$(cd "$out" && "$out/venv/bin/python" -c "import sgd_icp; print(sgd_icp.__file__)")
case "$location" in
  "$out/venv/"*) ;;
  *) echo "package_test: sgd_icp imported from $location, not from the venv" >&2; exit 1 ;;
esac
status=0
(cd "$out" && "$out/venv/bin/python" -m pytest "$repo/tests/python" -q -p no:cacheprovider \
  --rootdir "$repo") || status=$?
echo "package_test: done in $(($(date +%s) - start)) s"
exit "$status"
