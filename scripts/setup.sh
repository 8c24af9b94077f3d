#!/usr/bin/env bash
# Installs what sgd-icp needs to build and test on Debian 12, idempotently: packages already
# present are not touched, and apt-get update runs only when something is missing.
set -euo pipefail

packages=(build-essential cmake pkg-config libeigen3-dev libnanoflann-dev libcli11-dev
  nlohmann-json3-dev liblzf-dev libstb-dev libgtest-dev libbenchmark-dev python3
  python3-dev python3-venv
  clang-14 libclang-rt-14-dev llvm-14)  # the last three: scripts/fuzz.sh (docs/fuzzing.md)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all build dependencies present"
fi
