#!/usr/bin/env bash
# CI: builds the libFuzzer targets of fuzz/ with clang (ASan + UBSan) and
# runs each for a short time from its seed corpus. Fails on any crash, leak,
# sanitizer report or timeout; the input that did it is left in
# build-fuzz/artifacts/ (copy it to fuzz/crashes/ and add a regression test).
#   scripts/ci_fuzz.sh                  45 s per target
#   FUZZ_SECONDS=600 scripts/ci_fuzz.sh fuzz_config   longer, one target
set -euo pipefail
cd "$(dirname "$0")/.."

# clang and its runtime (libclang_rt.fuzzer*) are not in bootstrap.sh's list:
# only this step needs them. Installed only if missing.
scripts/apt_install.sh clang libclang-rt-14-dev

build_dir=${GTRACK_FUZZ_DIR:-build-fuzz}
seconds=${FUZZ_SECONDS:-45}
if [ ! -f "$build_dir/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S fuzz -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo
fi
cmake --build "$build_dir" --parallel "${JOBS:-2}"

source scripts/sanitizer_env.sh
targets=("$@")
((${#targets[@]})) || targets=(fuzz_config fuzz_data_defined fuzz_stimulus_log fuzz_parameter_vector fuzz_tracker_state fuzz_pose_table fuzz_dicom fuzz_image_header)
mkdir -p "$build_dir/artifacts"
status=0
for t in "${targets[@]}"; do
  # Every crash input kept so far must stay fixed (or skipped, see
  # fuzz/targets/toml_known_bugs.hpp) before new inputs are tried.
  if compgen -G "fuzz/crashes/*" >/dev/null; then
    "$build_dir/$t" -runs=0 fuzz/crashes/* >"$build_dir/$t.replay.log" 2>&1 ||
      { echo "ci_fuzz: $t fails on a kept crash input; see $build_dir/$t.replay.log"; status=1; continue; }
  fi
  # The seeds stay small and reviewed in git; the corpus that grows lives in
  # the build dir and is reused by the next run on this machine.
  work="$build_dir/corpus/$t"
  mkdir -p "$work"
  cp -n fuzz/corpus/"$t"/* "$work"/ 2>/dev/null || true
  log="$build_dir/$t.log"
  if "$build_dir/$t" "$work" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
       -max_len=8192 -print_final_stats=1 -artifact_prefix="$build_dir/artifacts/$t-" >"$log" 2>&1; then
    execs=$(awk '/stat::number_of_executed_units/ {print $2; exit}' "$log")
    cov=$(awk '/DONE/ && match($0, /cov: [0-9]+/) {c = substr($0, RSTART, RLENGTH)} END {print c}' "$log")
    echo "ci_fuzz: $t ok: ${execs:-?} executions in ${seconds}s, ${cov:-cov: ?}, corpus $(ls "$work" | wc -l) inputs"
  else
    echo "ci_fuzz: $t FAILED; the end of $log:"
    tail -40 "$log"
    status=1
  fi
done
exit $status
