#!/usr/bin/env bash
# Sets up gtrack on a fresh Debian 12 machine: installs the Debian packages it
# needs (apt-get, only those missing), configures and builds into ./build.
# Safe to run again: each step is skipped or incremental when already done.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libopencv-dev libtiff-dev
  libegl-dev libgl-dev libegl1-mesa-dev libegl-mesa0 libgl1-mesa-dri
  libboost-dev libboost-program-options-dev
  libtomlplusplus-dev libspdlog-dev
  libgtest-dev libgmock-dev libbenchmark-dev
)
scripts/apt_install.sh "${packages[@]}"

build_dir=${GTRACK_BUILD_DIR:-build}
if [ ! -f "$build_dir/build.ninja" ]; then
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release
fi
cmake --build "$build_dir" --parallel "$(nproc)"
