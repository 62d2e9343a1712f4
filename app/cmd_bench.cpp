// gtrack bench: throughput of every render backend and of the OpenCV
// baseline, in one run, on the same scene (bench.hpp): the hydrogel gripper
// ~114 px across at 256x256. Hypotheses per second for batches of --batch
// (32), and frames per second of the paper's PSO (N = 32, G = 25) per
// backend.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include "command.hpp"
#include "gtrack/bench.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/renderer.hpp"
#include "gtrack/results.hpp"

namespace po = boost::program_options;

namespace {

constexpr int kSide = 256;
constexpr double kGripperPx = 114;

struct Measured {
  std::optional<double> value;
  std::string note = {};  // why there is no value
};

std::string json_number(const std::optional<double>& v) {
  if (!v) return "null";
  std::ostringstream os;
  os.precision(6);
  os << *v;
  return os.str();
}

std::string human(const std::optional<double>& v) {
  if (!v) return "-";
  char buf[32];
  if (*v >= 1000) {
    std::snprintf(buf, sizeof buf, "%.1fk", *v / 1000);
  } else {
    std::snprintf(buf, sizeof buf, "%.1f", *v);
  }
  return buf;
}

// Makes a renderer, or says why it cannot be made.
template <class Make>
std::unique_ptr<gtrack::Renderer> try_make(Make make, int threads, std::string& why) {
  gtrack::RenderOptions o;
  o.threads = threads;
  try {
    return make(o);
  } catch (const gtrack::Error& e) {
    why = e.what();
    return nullptr;
  }
}

int run_bench(const gtrack::cli::CommonOptions& common, const po::variables_map& vm) {
  const double seconds = vm["seconds"].as<double>();
  if (!(seconds > 0 && seconds <= 3600)) throw gtrack::cli::UsageError("--seconds must be in (0, 3600]");
  const int batch = vm["batch"].as<int>();
  if (batch < 1 || batch > 4096) throw gtrack::cli::UsageError("--batch must be in 1-4096 hypotheses");
  const bool json = vm.count("json") > 0;
  const int rounds = vm["rounds"].as<int>();
  if (rounds < 1 || rounds > 100) throw gtrack::cli::UsageError("--rounds must be in 1-100");
  const int all = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  std::string gripper_source;
  const gtrack::ArticulatedModel model = gtrack::load_bench_gripper(common.plugin_paths, gripper_source);
  const gtrack::BenchScene scene = gtrack::make_bench_scene(model, kSide, kGripperPx);
  gtrack::logger().info("bench: {} at {}x{}, {:.0f} px across, {} s per measurement", gripper_source, kSide, kSide,
                        kGripperPx, seconds);

  // The backends take turns, round after round, each measurement's time
  // split over the rounds: a burst of other work on the machine then
  // falls on every backend alike rather than on whichever ran during it.
  // Each figure is the median of its rounds, and a ratio the median of
  // the rounds' own ratios.
  const double slice = seconds / rounds;
  struct Backend {
    std::unique_ptr<gtrack::Renderer> renderer;
    std::string why = {};
    bool frames = false;  // also PSO frames/s
    std::vector<double> hyp = {}, fps = {};
  };
  std::string why;
  Backend cpu1{try_make(gtrack::make_cpu_renderer, 1, why)}, cpu_all{try_make(gtrack::make_cpu_renderer, all, why)},
      base1{try_make(gtrack::make_opencv_baseline, 1, why)}, base_all{try_make(gtrack::make_opencv_baseline, all, why)},
      gl;
  for (const Backend* b : {&cpu1, &cpu_all, &base1, &base_all}) {
    if (!b->renderer) throw gtrack::Error("bench: " + why);
  }
  gl.renderer = try_make(gtrack::make_gl_renderer, 0, gl.why);
  cpu_all.frames = gl.frames = true;
  std::vector<double> ratio1, ratio_n;
  std::vector<double> gl_hyp_ratio, gl_fps_ratio;  // gl over cpu (all threads), round by round
  for (int round = 0; round < rounds; ++round) {
    for (Backend* b : {&cpu1, &cpu_all, &base1, &base_all, &gl}) {
      if (!b->renderer) continue;
      try {
        b->hyp.push_back(gtrack::measure_hypotheses(*b->renderer, scene, slice, batch).per_second);
        if (b->frames) b->fps.push_back(gtrack::measure_pso_frames(*b->renderer, scene, slice).per_second);
      } catch (const gtrack::Error& e) {
        // The gl backend failing part way (a lost context): the others go
        // on. The cpu and OpenCV backends have nothing to fail on.
        if (b != &gl) throw;
        b->why = e.what();
        b->renderer.reset();
        b->hyp.clear();
        b->fps.clear();
      }
    }
    ratio1.push_back(cpu1.hyp.back() / base1.hyp.back());
    ratio_n.push_back(cpu_all.hyp.back() / base_all.hyp.back());
    if (gl.renderer && !gl.hyp.empty()) {
      gl_hyp_ratio.push_back(gl.hyp.back() / cpu_all.hyp.back());
      gl_fps_ratio.push_back(gl.fps.back() / cpu_all.fps.back());
    }
  }
  const auto median = [](std::vector<double> v) -> std::optional<double> {
    if (v.empty()) return std::nullopt;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  };
  const auto range = [](const std::vector<double>& v) {
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    char text[48];
    std::snprintf(text, sizeof text, "%.3g-%.3g", *lo, *hi);
    return std::string(text);
  };
  const Measured m_cpu1{median(cpu1.hyp)}, m_cpu_all{median(cpu_all.hyp)}, m_cpu_frames{median(cpu_all.fps)},
      m_base1{median(base1.hyp)}, m_base_all{median(base_all.hyp)}, m_gl{median(gl.hyp), gl.why},
      m_gl_frames{median(gl.fps), gl.why};
  const double ratio_one = *median(ratio1), ratio_all = *median(ratio_n);
  // The gl backend's ratios only from rounds it finished (it may fail part way).
  const std::optional<double> gl_over_cpu = m_gl.value ? median(gl_hyp_ratio) : std::nullopt;
  const std::optional<double> gl_over_cpu_frames = m_gl.value ? median(gl_fps_ratio) : std::nullopt;
  if (json) {
    std::cout << "{\"hypotheses_per_s\": {\"cpu\": " << json_number(m_cpu_all.value)
              << ", \"gl\": " << json_number(m_gl.value) << ", \"opencv_baseline\": " << json_number(m_base_all.value)
              << "},\n \"frames_per_s\": {\"cpu\": " << json_number(m_cpu_frames.value)
              << ", \"gl\": " << json_number(m_gl_frames.value) << "},\n"
              << " \"frames_per_s_is\": \"full PSO search of one frame: N=32 particles, G=25 generations, cost "
                 "of eq. (1); no segmentation or I/O\",\n"
              << " \"cpu_hypotheses_per_s_by_threads\": {\"1\": " << json_number(m_cpu1.value) << ", \"" << all
              << "\": " << json_number(m_cpu_all.value) << "},\n"
              << " \"opencv_baseline_hypotheses_per_s_by_threads\": {\"1\": " << json_number(m_base1.value) << ", \""
              << all << "\": " << json_number(m_base_all.value) << "},\n"
              << " \"cpu_over_opencv_baseline\": {\"1\": " << json_number(ratio_one) << ", \"" << all
              << "\": " << json_number(ratio_all) << "},\n"
              << " \"threads\": " << all << ", \"batch\": " << batch << ", \"render_size\": [" << kSide << ", " << kSide
              << "], \"gripper_px\": " << kGripperPx << ", \"gripper\": " << gtrack::json_string(gripper_source)
              << ", \"seconds_per_measurement\": " << seconds << ", \"rounds\": " << rounds
              << ", \"cpu_over_opencv_baseline_range\": {\"1\": \"" << range(ratio1) << "\", \"" << all << "\": \""
              << range(ratio_n) << "\"}";
    std::cout << ",\n \"gl_over_cpu\": {\"hypotheses_per_s\": " << json_number(gl_over_cpu)
              << ", \"frames_per_s\": " << json_number(gl_over_cpu_frames) << "}";
    if (!m_gl.value) std::cout << ",\n \"gl_unavailable\": " << gtrack::json_string(m_gl.note);
    std::cout << "}\n";
    return 0;
  }

  std::printf("gtrack bench: %s, %dx%d render, gripper ~%.0f px across, batches of %d\n\n", gripper_source.c_str(),
              kSide, kSide, kGripperPx, batch);
  std::printf("%-18s %12s %14s %16s\n", "backend", "threads", "hypotheses/s", "PSO frames/s");
  std::printf("%-18s %12d %14s %16s\n", "cpu", 1, human(m_cpu1.value).c_str(), "");
  std::printf("%-18s %12d %14s %16s\n", "cpu", all, human(m_cpu_all.value).c_str(), human(m_cpu_frames.value).c_str());
  std::printf("%-18s %12s %14s %16s\n", "gl", "", human(m_gl.value).c_str(), human(m_gl_frames.value).c_str());
  std::printf("%-18s %12d %14s %16s\n", "opencv_baseline", 1, human(m_base1.value).c_str(), "");
  std::printf("%-18s %12d %14s %16s\n", "opencv_baseline", all, human(m_base_all.value).c_str(), "");
  std::printf("\ncpu / opencv_baseline: %.1fx (1 thread), %.1fx (%d threads): the medians of %d rounds' ratios "
              "(ranges %s and %s)\n",
              ratio_one, ratio_all, all, rounds, range(ratio1).c_str(), range(ratio_n).c_str());
  if (gl_over_cpu && gl_over_cpu_frames) {
    std::printf("gl / cpu (%d threads): %.3gx hypotheses/s, %.3gx PSO frames/s: the medians of the rounds' ratios "
                "(ranges %s and %s)\n",
                all, *gl_over_cpu, *gl_over_cpu_frames, range(gl_hyp_ratio).c_str(), range(gl_fps_ratio).c_str());
  }
  std::printf("PSO frame = N=32 particles x G=25 generations with the cost of eq. (1); no segmentation or I/O\n");
  if (!m_gl.value) std::printf("gl: not measured: %s\n", m_gl.note.c_str());
  return 0;
}

}  // namespace

GTRACK_COMMAND("bench", "throughput of every render backend and of the OpenCV baseline, in one run",
               [](po::options_description& d) {
                 d.add_options()("json", "print one JSON object instead of a table")(
                     "seconds", po::value<double>()->default_value(1.0),
                     "time spent on each measurement, over all rounds")(
                     "rounds", po::value<int>()->default_value(3),
                     "the backends take turns this many times; each figure is the median of its rounds")(
                     "batch", po::value<int>()->default_value(32),
                     "hypotheses per batch for hypotheses/s (a swarm's N; PSO frames/s keep N = 32)");
               },
               run_bench, {})
