#!/usr/bin/env bash
# CI: the test suite built with AddressSanitizer + UndefinedBehaviorSanitizer
# (and LeakSanitizer at exit), in its own build dir so that the normal build
# is untouched. Budget: ~15 min on 2 cores, build included.
#   scripts/ci_sanitize.sh              build-asan, whole suite minus $exclude
#   GTRACK_ASAN_DIR=... JOBS=... scripts/ci_sanitize.sh
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=${GTRACK_ASAN_DIR:-build-asan}
jobs=${JOBS:-2}
# -O1: fast enough for the tests, keeps frames and lines exact in reports.
if [ ! -f "$build_dir/build.ninja" ]; then
  cmake -S . -B "$build_dir" -G Ninja \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
    -DGTRACK_SANITIZE=ON -DGTRACK_BUILD_BENCH=OFF
fi
cmake --build "$build_dir" --parallel "$jobs"

source scripts/sanitizer_env.sh
# Tests excluded under sanitizers only because they take minutes there (the
# normal build runs them); none is excluded for a sanitizer finding.
exclude=${GTRACK_ASAN_EXCLUDE:-'^(Soak\.)'}
ctest --test-dir "$build_dir" --output-on-failure -j"$jobs" --timeout 900 -E "$exclude"
