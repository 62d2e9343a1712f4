// gtrack synth as a library call: plan, draw in parallel, write the folder.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <opencv2/imgcodecs.hpp>
#include <mutex>
#include <thread>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/results.hpp"
#include "gtrack/sequence_io.hpp"
#include "gtrack/synth.hpp"
#include "gtrack/text_file.hpp"
#include "tracking/replace_file.hpp"

namespace gtrack {

namespace fs = std::filesystem;

SynthSummary write_synthetic_sequence(const Setup& setup, const SynthOptions& options, const fs::path& out) {
  const auto start = std::chrono::steady_clock::now();
  // Planned before the folder is touched: a config error leaves it as it was.
  const SynthPlan plan = plan_sequence(setup, options);
  std::error_code ec;
  // A lab's log kept as OUT/stimulus.csv would be replaced by the sequence's
  // own (its readings at the frames only): refused before anything is removed.
  for (const char* name : {"ground_truth.csv", "stimulus.csv", "sequence.toml"}) {
    if (options.stimulus_log && fs::equivalent(out / name, *options.stimulus_log, ec)) {
      throw InputError(options.stimulus_log->string() + ": is the stimulus log the sequence is made from; writing " +
                       "the sequence to " + out.string() + " would replace it with its " + name +
                       "; expected another --out");
    }
  }
  fs::create_directories(out / "frames", ec);
  if (ec) throw InputError(out.string() + ": cannot create the folder (" + ec.message() + ")");
  // The frames of an earlier sequence in the same folder would be tracked
  // with this one's, and its truth, left beside frames of this one by a run
  // stopped part way (Ctrl-C), would score them: both go first. The truth
  // is written once every frame is.
  int stale = remove_frame_images(out / "frames");
  for (const char* name : {"ground_truth.csv", "stimulus.csv", "sequence.toml"}) {
    // The config this run reads (an earlier sequence.toml given as --config) stays until replaced.
    if (!setup.root.source().empty() && fs::equivalent(out / name, setup.root.source(), ec)) continue;
    stale += fs::remove(out / name, ec);
  }
  for (const auto& entry : fs::directory_iterator(out / "frames", ec)) {
    if (entry.path().extension() == ".tmp") fs::remove(entry.path(), ec);  // a frame a stopped run was writing
  }
  if (stale > 0) logger().info("{}: removed the files of an earlier sequence", out.string());

  const int n = static_cast<int>(plan.frames.size());
  std::vector<SynthVisibility> vis(n);
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::string failure;
  std::mutex failure_mutex;
  // Frames are independent given the plan: draw them on every core.
  auto worker = [&] {
    for (int i = next++; i < n && !failed; i = next++) {
      try {
        const cv::Mat img = render_frame(setup, plan, i, &vis[i]);
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", i);
        const fs::path file = out / "frames" / name;
        // Fast PNG compression: the sequence is written once and read often.
        // Written aside and renamed: a frame is whole or absent.
        std::vector<std::uint8_t> png;
        if (!cv::imencode(".png", img, png, {cv::IMWRITE_PNG_COMPRESSION, 1})) {
          throw InputError(file.string() + ": cannot encode");
        }
        detail::replace_file(file, std::string(png.begin(), png.end()));
      } catch (const std::exception& e) {
        std::lock_guard lock(failure_mutex);
        failure = e.what();
        failed = true;
      }
    }
  };
  int threads = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  // More threads than cores only wait, each with a frame in memory.
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  threads = std::clamp(threads, 1, std::max(1, std::min(n, cores)));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (failed) throw Error("synthetic sequence: " + failure);

  {
    std::ostringstream csv;
    csv << "frame,value\n";
    for (const auto& f : plan.frames) csv << f.frame << "," << f.stimulus << "\n";
    write_text_file(out / "stimulus.csv", csv.str());
  }
  SynthSummary s;
  s.frames = n;
  s.duration_s = n / plan.preset.frame_rate_hz;
  s.stimulus_low = plan.preset.stimulus_low;
  s.stimulus_high = plan.preset.stimulus_high;
  if (!plan.frames.empty()) {
    const auto [lo, hi] = std::minmax_element(plan.frames.begin(), plan.frames.end(),
                                              [](const auto& a, const auto& b) { return a.stimulus < b.stimulus; });
    s.stimulus_min = lo->stimulus;
    s.stimulus_max = hi->stimulus;
  }
  const int F = setup.model().fingers();
  for (const auto& f : plan.frames) {
    if (F == 0) break;
    s.joint_min_deg = std::min(s.joint_min_deg, f.truth.tail(F).minCoeff());
    s.joint_max_deg = std::max(s.joint_max_deg, f.truth.tail(F).maxCoeff());
  }
  {
    std::ostringstream csv;
    csv << pose_table_header(setup.model().fingers(), {"visible", "in_view", "occluded"}) << "\n";
    for (int i = 0; i < n; ++i) {
      csv << pose_table_row(i, plan.frames[i].truth, {vis[i].visible, vis[i].in_view, vis[i].occluded}) << "\n";
      if (vis[i].occluded > 0.01) {
        ++s.occluded_frames;
        s.mean_occlusion += vis[i].occluded;
      }
      s.max_occlusion = std::max(s.max_occlusion, vis[i].occluded);
      if (vis[i].in_view < 0.10) {
        ++s.out_of_view_frames;
      } else if (vis[i].in_view < 0.99) {
        ++s.partly_out_frames;
      }
    }
    write_text_file(out / "ground_truth.csv", csv.str());
  }
  if (s.occluded_frames) s.mean_occlusion /= s.occluded_frames;
  s.sequence_config = out / "sequence.toml";
  write_sequence_config(setup.root, plan, s.sequence_config, setup.plugin_paths);
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

}  // namespace gtrack
