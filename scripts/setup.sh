#!/usr/bin/env bash
# Installs what sgd-icp needs to build and test on Debian 12, idempotently: packages already
# present are not touched, and apt-get update runs only when something is missing.
#   scripts/setup.sh            build and test dependencies
#   scripts/setup.sh --open3d   also the libraries the Open3D wheel loads (docs/python.md)
set -euo pipefail

packages=(build-essential cmake pkg-config libeigen3-dev libnanoflann-dev libcli11-dev
  nlohmann-json3-dev liblzf-dev libstb-dev libgtest-dev libbenchmark-dev python3
  python3-dev python3-venv
  clang-14 libclang-rt-14-dev llvm-14)  # the last three: scripts/fuzz.sh (docs/fuzzing.md)
for arg in "$@"; do
  case "$arg" in
    --open3d) packages+=(libegl1 libgl1 libx11-6 libusb-1.0-0 libudev1 libidn2-0 libgomp1) ;;
    *) echo "setup: unknown option $arg (expected --open3d)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  # `env` passes DEBIAN_FRONTEND through sudo, which would drop it from the environment.
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all build dependencies present"
fi
