#!/usr/bin/env bash
# The plugin SDK as a lab uses it: install gtrack to a fresh prefix, build the
# out-of-tree examples (a sensor, a gripper and two stimuli, one of them on
# the SDK's hysteresis model) against it, list
# them with the installed gtrack, and track short synthetic sequences with
# them and with the gripper defined only in TOML, checking the errors against
# thresholds.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${GTRACK_BUILD_DIR:-build}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"

cmake --install "$build_dir" --prefix "$prefix" > "$work/install.log"
gtrack="$prefix/bin/gtrack"
for ex in light_stimulus three_finger_gripper telecentric_sensor field_latch; do
  cmake -S "examples/$ex" -B "$work/$ex" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release > "$work/$ex.log"
  cmake --build "$work/$ex" >> "$work/$ex.log"
done
# Installed beside gtrack's own plugins, a plugin is found without a path.
cmake --install "$work/light_stimulus" >> "$work/light_stimulus.log"
env -u GTRACK_PLUGIN_PATH "$gtrack" plugins | grep -q $'^stimulus\tlight_intensity\t' ||
  { echo "ci_examples: light_intensity installed with GTRACK_PLUGIN_INSTALL_DIR is not found"; exit 1; }
paths=(--plugin-path "$work/light_stimulus" --plugin-path "$work/three_finger_gripper" --plugin-path "$work/telecentric_sensor"
       --plugin-path "$work/field_latch")
listing=$(env -u GTRACK_PLUGIN_PATH "$gtrack" plugins "${paths[@]}")
echo "$listing"
grep -q $'^stimulus\tlight_intensity\t' <<< "$listing" || { echo "ci_examples: light_intensity not listed"; exit 1; }
grep -q $'^gripper\tthree_finger_gripper\t' <<< "$listing" || { echo "ci_examples: three_finger_gripper not listed"; exit 1; }
grep -q $'^sensor\ttelecentric_microscope\t' <<< "$listing" || { echo "ci_examples: telecentric_microscope not listed"; exit 1; }
grep -q $'^stimulus\tfield_latch\t' <<< "$listing" || { echo "ci_examples: field_latch not listed"; exit 1; }

# mean of a metric in an evaluation JSON
mean_of() { sed -n "s/.*\"$2\": {\"mean\": \([-0-9.e+]*\).*/\1/p" "$1" | head -n1; }
check() {  # check FILE METRIC MAX LABEL
  local v; v=$(mean_of "$1" "$2")
  [ -n "$v" ] || { echo "ci_examples: $4: no $2 in $1"; exit 1; }
  if awk -v v="$v" -v m="$3" 'BEGIN { exit !(v <= m) }'; then
    echo "ci_examples: $4: $2 mean $v <= $3"
  else
    echo "ci_examples: $4: $2 mean $v exceeds $3"; exit 1
  fi
}
# Thresholds catch a lost track (errors of a lost track are in millimetres and
# tens of degrees), not the accuracy targets; docs/RESULTS.md has the measured
# figures, which are well above those targets today.
run_setup() {  # run_setup NAME CONFIG FRAMES MAX_INPLANE_UM MAX_ORIENT_DEG MAX_JOINT_DEG
  local name=$1 config=$2 frames=$3 out="$work/$1"
  "$gtrack" synth --config "$config" --out "$out/seq" --frames "$frames" --seed 7 "${paths[@]}" > "$out.synth.log"
  "$gtrack" track --config "$out/seq/sequence.toml" --input "$out/seq/frames" --stimulus "$out/seq/stimulus.csv" \
    --out "$out/track" --log-level warn "${paths[@]}" > "$out.track.log" 2>&1
  "$gtrack" eval --truth "$out/seq/ground_truth.csv" --estimates "$out/track/estimates.csv" \
    --json "$out/eval.json" "${paths[@]}" | tail -n 12
  check "$out/eval.json" position_inplane_um "$4" "$name"
  check "$out/eval.json" orientation_deg "$5" "$name"
  check "$out/eval.json" joint_deg "$6" "$name"
}

# The example setup's [synth] table drives the light through the plugin's
# fold band (5 to 80 mW/cm2), so its sequence folds and unfolds the gripper;
# check that it does. The three-finger gripper is flat when open and the
# telecentric sensor exactly orthographic, so the tilt's sign is not in the
# image until it folds: over swarm seeds 1-5 this sequence gives 2.0-6.0 um,
# 6.4-10.6 deg and 1.7-2.8 deg; the light plugin without its settle time (the
# joints forced folded as soon as the light crosses the band) gives 85 um,
# 26 deg and 10 deg, and fails these bounds.
run_setup examples examples/example_setup.toml 60 "${EXAMPLE_MAX_UM:-30}" "${EXAMPLE_MAX_DEG:-30}" "${EXAMPLE_MAX_JOINT_DEG:-6}"
folded=$(sed -n 's/.*joints: [-0-9.e+]* to \([-0-9.e+]*\) deg.*/\1/p' "$work/examples.synth.log")
awk -v v="${folded:-0}" 'BEGIN { exit !(v >= 20) }' || { echo "ci_examples: the example sequence does not fold (joints up to '$folded' deg)"; exit 1; }
echo "ci_examples: examples: the joints fold to $folded deg"
# The TOML-defined gripper is 2.9 mm across: a lost track is off by a
# millimetre or more. On this one 60-frame sequence the swarm's seed alone
# moves the errors between 11.6 and 43.8 um, 3.2 and 13.3 deg, and up to 4.2
# deg in the joints (docs/RESULTS.md, "How much the swarm's own seed moves
# these numbers"), so the bounds sit above that spread; the tracker before
# the occlusion rim (114 um, 21 deg) fails them.
run_setup custom_gripper "$prefix/share/gtrack/configs/microscope_custom_gripper.toml" 60 \
  "${CUSTOM_MAX_UM:-100}" "${CUSTOM_MAX_DEG:-20}" "${CUSTOM_MAX_JOINT_DEG:-6}"
# The SDK's hysteresis model under a lab's own keys and unit (mT): a field
# from 3 to 12 mT releases the latch at 9 mT, and the two-finger gripper
# folds. The gripper is 0.75 mm long: a lost track is off by hundreds of um.
run_setup field_latch examples/field_setup.toml 40 "${FIELD_MAX_UM:-30}" "${FIELD_MAX_DEG:-45}" "${FIELD_MAX_JOINT_DEG:-10}"
folded=$(sed -n 's/.*joints: [-0-9.e+]* to \([-0-9.e+]*\) deg.*/\1/p' "$work/field_latch.synth.log")
awk -v v="${folded:-0}" 'BEGIN { exit !(v >= 20) }' || { echo "ci_examples: the field sequence does not fold (joints up to '$folded' deg)"; exit 1; }
echo "ci_examples: field_latch: the joints fold to $folded deg"
echo "ci_examples: passed"
