// Tracking a synthetic sequence in-process and scoring it.
//
// The demo, the sweep (paper Fig. 6) and the end-to-end test all do the
// same three steps on a folder written by write_synthetic_sequence: load
// its sequence.toml, run the Tracker frame by frame over frames/ with
// stimulus.csv, and evaluate the estimates against ground_truth.csv. The
// engine config can be altered in between (particles, generations), which is
// what a sweep needs; frames are read from disk as they are tracked, so a
// long sequence does not have to fit in memory.
#pragma once

#include <filesystem>
#include <functional>

#include "gtrack/engine_config.hpp"
#include "gtrack/evaluation.hpp"
#include "gtrack/export.hpp"
#include "gtrack/sequence_io.hpp"
#include "gtrack/setup.hpp"

namespace gtrack {

struct BenchmarkRun {
  PoseTable estimates;
  Evaluation evaluation;
  int frames = 0;
  double tracker_ms = 0;     // mean per frame: segmentation + PSO (Estimate::ms)
  double tracker_fps = 0;    // 1000 / tracker_ms
  double wall_s = 0;         // including reading the frames
  std::string renderer;
};

// Loads dir/sequence.toml with the given plugin folders.
GTRACK_API Setup load_synthetic_setup(const std::filesystem::path& dir,
                                      const std::vector<std::filesystem::path>& plugin_paths = {});

// Tracks dir/frames with `config` and evaluates against dir/ground_truth.csv.
// `max_frames` < 0: all frames. `on_frame` (optional) sees each frame index.
GTRACK_API BenchmarkRun run_synthetic_benchmark(const Setup& setup, const EngineConfig& config,
                                                const std::filesystem::path& dir, int max_frames = -1,
                                                const EvalOptions& eval_options = {},
                                                const std::function<void(int)>& on_frame = {});

}  // namespace gtrack
