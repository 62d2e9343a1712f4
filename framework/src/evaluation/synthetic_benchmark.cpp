// Track a synthetic folder with the library's Tracker, then evaluate.
#include "gtrack/synthetic_benchmark.hpp"

#include <chrono>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>

#include "gtrack/error.hpp"
#include "gtrack/stimulus_log.hpp"
#include "gtrack/tracker.hpp"

namespace gtrack {

namespace fs = std::filesystem;

Setup load_synthetic_setup(const fs::path& dir, const std::vector<fs::path>& plugin_paths) {
  SetupOptions so;
  so.plugin_paths = plugin_paths;
  return load_setup(dir / "sequence.toml", so);
}

BenchmarkRun run_synthetic_benchmark(const Setup& setup, const EngineConfig& config, const fs::path& dir,
                                     int max_frames, const EvalOptions& eval_options,
                                     const std::function<void(int)>& on_frame) {
  const auto start = std::chrono::steady_clock::now();
  const PoseTable truth = read_truth_table(dir / "ground_truth.csv");
  const StimulusLog log = StimulusLog::load(dir / "stimulus.csv");
  const double fps = config.tracker.fps > 0 ? config.tracker.fps : 30.0;
  int n = static_cast<int>(truth.rows.size());
  if (max_frames >= 0) n = std::min(n, max_frames);

  Tracker tracker(setup, config);
  BenchmarkRun run;
  run.renderer = tracker.renderer().name();
  run.estimates.fingers = setup.model().fingers();
  double ms = 0;
  for (int i = 0; i < n; ++i) {
    const int frame = truth.rows[i].frame;
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", frame);
    const fs::path file = dir / "frames" / name;
    const cv::Mat img = cv::imread(file.string(), cv::IMREAD_COLOR);
    if (img.empty()) throw InputError(file.string() + ": cannot read the frame");
    const double t = frame / fps;
    std::optional<double> stimulus = log.value_at(frame, t);
    if (!stimulus && log.rows() > 0) stimulus = log.nearest(frame, t);
    const Estimate e = tracker.process(img, frame, t, stimulus);
    PoseRow row;
    row.frame = frame;
    row.h = e.hypothesis;
    row.status = to_string(e.status);
    run.estimates.rows.push_back(std::move(row));
    ms += e.ms;
    if (on_frame) on_frame(frame);
  }
  // Only the frames tracked are judged: a shortened run is not "lost" beyond its end.
  PoseTable judged = truth;
  judged.rows.resize(n);
  run.evaluation = evaluate(setup.model(), judged, run.estimates, eval_options, setup.sensor.get());
  run.frames = n;
  run.tracker_ms = n ? ms / n : 0;
  run.tracker_fps = run.tracker_ms > 0 ? 1000.0 / run.tracker_ms : 0;
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace gtrack
