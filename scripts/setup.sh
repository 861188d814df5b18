#!/usr/bin/env bash
# Installs every Debian package atmos needs to build, test and render.
# Idempotent and non-interactive: packages already present are skipped, so it is
# safe (and fast) to run twice.
# clang builds the tests' sanitizer build (scripts/test.sh) and the fuzz
# targets (scripts/fuzz.sh); GCC builds everything else.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libglm-dev nlohmann-json3-dev libcli11-dev libtinyexr-dev libstb-dev
  libtbb-dev libgtest-dev libgmock-dev libbenchmark-dev
  libepoxy-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev
  libeigen3-dev liblapacke-dev python3-matplotlib
  libgdal-dev libnetcdf-dev
  xplanet-images xplanet gmt-gshhg-low kstars-data
  libglfw3-dev libimgui-dev xvfb xauth
  libopenxr-dev libopenxr-loader1
  clang libclang-rt-14-dev
)

if [ $# -gt 0 ]; then
  echo "setup: no options (got $*)" >&2
  exit 2
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages already installed"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
