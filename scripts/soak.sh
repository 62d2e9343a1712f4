#!/usr/bin/env bash
# Soak test (not in CI): `gtrack track` over a long sequence, watching the
# process from outside for memory growth and throughput drift.
#
# A short synthetic sequence (128x128, hydrogel gripper, N=32, G=25, cpu
# backend) is made once with `gtrack synth` and played back and forth
# (0..59, 58..1, 0..59, ...) as a folder of hard links, with the stimulus log
# stretched the same way, so motion stays continuous and every frame goes
# through the whole pipeline: PNG decode, segmentation, PSO, result rows.
# The RSS of the tracker (/proc/PID/status VmRSS) and the frames written so
# far are sampled every SOAK_EVERY_S seconds.
#
#   scripts/soak.sh                      10000 frames with build/bin/gtrack
#   SOAK_FRAMES=20000 GTRACK_BIN=build-asan/bin/gtrack scripts/soak.sh
#
# Passes when, after warm-up (the first 10% of the frames), RSS grows by at
# most SOAK_MAX_GROWTH_KB and the frame rate of the last third is within
# SOAK_MAX_DRIFT_PCT of the second third's. Prints the figures recorded in
# docs/reliability.md.
set -euo pipefail
cd "$(dirname "$0")/.."

bin=${GTRACK_BIN:-build/bin/gtrack}
frames=${SOAK_FRAMES:-10000}
every_s=${SOAK_EVERY_S:-1}
max_growth_kb=${SOAK_MAX_GROWTH_KB:-4096}
max_drift_pct=${SOAK_MAX_DRIFT_PCT:-20}
work=${SOAK_DIR:-build/soak}
base_frames=60

[ -x "$bin" ] || { echo "soak: $bin not found; build first (ninja -C build)"; exit 1; }
rm -rf "$work"
mkdir -p "$work/frames"

# The small setup the fault tests use too, on the cpu backend.
{ cat tests/data/microscope_128.toml; printf '[render]\nbackend = "cpu"\n'; } >"$work/small.toml"
"$bin" synth --config "$work/small.toml" --out "$work/seq" --frames "$base_frames" --seed 3 >/dev/null

# Frame i of the soak is frame pingpong(i) of the sequence.
period=$((2 * base_frames - 2))
{
  echo "frame,value"
  declare -A value
  while IFS=, read -r k v; do value[$k]=$v; done < <(tail -n +2 "$work/seq/stimulus.csv")
  for ((i = 0; i < frames; i++)); do
    p=$((i % period))
    ((p < base_frames)) || p=$((period - p))
    printf -v src "%06d.png" "$p"
    printf -v dst "%06d.png" "$i"
    ln "$work/seq/frames/$src" "$work/frames/$dst"
    echo "$i,${value[$p]}"
  done
} >"$work/stimulus.csv"
head -1 "$work/seq/stimulus.csv" | grep -q '^frame,' || { echo "soak: expected a frame-keyed stimulus log"; exit 1; }

"$bin" track --config "$work/seq/sequence.toml" --input "$work/frames" --stimulus "$work/stimulus.csv" \
  --out "$work/out" 2>"$work/track.log" &
pid=$!
samples="$work/samples.csv"
echo "t_s,frames,rss_kb" >"$samples"
start_ns=$(date +%s%N)
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  done_frames=$(($(wc -l 2>/dev/null <"$work/out/estimates.csv" || echo 1) - 1))
  ms=$((($(date +%s%N) - start_ns) / 1000000))
  [ -n "$rss" ] && printf "%d.%03d,%d,%d\n" $((ms / 1000)) $((ms % 1000)) "$done_frames" "$rss" >>"$samples"
  sleep "$every_s"
done
wait "$pid" || { echo "soak: gtrack track failed:"; tail -5 "$work/track.log"; exit 1; }

rows=$(($(wc -l <"$work/out/estimates.csv") - 1))
[ "$rows" -eq "$frames" ] || { echo "soak: $rows rows in estimates.csv, expected $frames"; exit 1; }

# Figures: RSS after warm-up vs at the end; frames/s per third of the run
# (from the samples: frames done against time).
awk -F, -v n="$frames" -v max_growth="$max_growth_kb" -v max_drift="$max_drift_pct" '
  NR == 1 { next }
  { t[++k] = $1; f[k] = $2; r[k] = $3 }
  END {
    warm = 0; peak = 0
    for (i = 1; i <= k; i++) {
      if (!warm && f[i] >= n / 10) { warm = i }
      if (warm && r[i] > peak) peak = r[i]
    }
    if (!warm || k < 6) { print "soak: too few samples; lower SOAK_EVERY_S"; exit 1 }
    # frames/s over [a, b) of the frame count, from the first samples past a and b
    split("", fps)
    for (third = 1; third <= 3; third++) {
      lo = n * (third - 1) / 3; hi = n * third / 3
      i0 = 0; i1 = 0
      for (i = 1; i <= k; i++) { if (!i0 && f[i] >= lo) i0 = i; if (f[i] <= hi) i1 = i }
      fps[third] = (t[i1] > t[i0]) ? (f[i1] - f[i0]) / (t[i1] - t[i0]) : 0
    }
    growth = r[k] - r[warm]
    drift = fps[2] > 0 ? 100 * (fps[3] - fps[2]) / fps[2] : 0
    printf "soak: %d frames in %.0f s; RSS %d kB after warm-up (frame %d), %d kB at the end, peak %d kB, growth %+d kB\n", \
      n, t[k], r[warm], f[warm], r[k], peak, growth
    printf "soak: frames/s by thirds: %.1f, %.1f, %.1f (last vs middle: %+.1f%%)\n", fps[1], fps[2], fps[3], drift
    bad = 0
    if (growth > max_growth) { printf "soak: FAIL: RSS grew by %d kB (> %d)\n", growth, max_growth; bad = 1 }
    if (drift < -max_drift) { printf "soak: FAIL: frame rate fell by %.1f%% (> %d%%)\n", -drift, max_drift; bad = 1 }
    if (!bad) print "soak: ok"
    exit bad
  }' "$samples"
