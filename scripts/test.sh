#!/usr/bin/env bash
# One command for a fresh Debian 12 machine: install dependencies, build with warnings as errors,
# run every C++ test (unit, real-data and CLI tests through CTest), then install the Python
# package with pip and run its tests (pytest tests/python). Real-data tests read ../shared/data
# beside the repository and skip when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
build_dir=${BUILD_DIR:-build}
ctest --test-dir "$build_dir" --output-on-failure -j"$(nproc)"

# Python: `pip install .` into the current Python (${PYTHON:-python3}), or into a venv in the
# build folder when that Python has no pip or is Debian's own (externally managed, PEP 668).
# SGDICP_PACKAGE_TEST=1 (CI does this): the packages as a user downloads them instead: `python -m
# build` makes the sdist and then the wheel from that sdist (a file the sdist lacks fails the
# build), the wheel with its [test] extra goes into a fresh venv, and the tests import that
# installed copy. The C++ core is compiled once either way.
python=${PYTHON:-python3}
package_test=${SGDICP_PACKAGE_TEST:-0}
needs_venv() {
  [ "$package_test" = 1 ] && return 0
  "$python" -m pip --version >/dev/null 2>&1 || return 0
  "$python" - <<'PY' || return 0
import os, sys, sysconfig
marker = os.path.join(sysconfig.get_path("stdlib"), "EXTERNALLY-MANAGED")
sys.exit(1 if sys.prefix == sys.base_prefix and os.path.isfile(marker) else 0)
PY
  return 1
}
if needs_venv; then
  echo "test: installing the Python package into the venv $build_dir/python-venv"
  [ "$package_test" = 1 ] && rm -rf "$build_dir/python-venv"
  python3 -m venv "$build_dir/python-venv"
  python="$(cd "$build_dir/python-venv" && pwd)/bin/python"
fi
pip_install() {
  "$python" -m pip install --quiet --disable-pip-version-check --root-user-action=ignore "$@"
}
pip_install pytest numpy scipy matplotlib  # scipy, matplotlib: the eval/ scripts' smoke tests
# Build requirements (scikit-build-core, pybind11) come from pyproject.toml; the module is built
# in the build folder, with warnings as errors.
echo "test: building and installing the Python package (compiles the C++ core again: a few minutes the first time)"
python_build=$(cd "$build_dir" && pwd)/python
define_werror=cmake.define.SGDICP_WARNINGS_AS_ERRORS=ON
if [ "$package_test" = 1 ]; then
  dist="$build_dir/dist"
  rm -rf "$dist"
  pip_install build
  "$python" -m build --outdir "$dist" -C build-dir="$python_build" -C "$define_werror" .
  wheel=$(ls "$dist"/*.whl)
  echo "test: built $(basename "$(ls "$dist"/*.tar.gz)") and $(basename "$wheel"); installing the wheel"
  pip_install "$wheel[test]"
  # The installed package, not python/ of this checkout, must be the one the tests import.
  location=$(cd / && "$python" -c "import sgd_icp; print(sgd_icp.__file__)")
  case "$location" in
    "${python%/bin/python}/"*) ;;
    *) echo "test: sgd_icp is imported from $location, not from the venv" >&2; exit 1 ;;
  esac
else
  pip_install --config-settings=build-dir="$python_build" --config-settings="$define_werror" .
fi

case "$build_dir" in
  /*) cli="$build_dir/sgdicp" ;;
  *) cli="$PWD/$build_dir/sgdicp" ;;
esac
status=0
SGDICP_BIN="$cli" "$python" -m pytest tests/python -q -p no:cacheprovider || status=$?
if [ "$status" -eq 5 ]; then
  echo "test: pytest collected no tests in tests/python" >&2
  exit 1
fi
exit "$status"
