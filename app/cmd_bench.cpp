// gtrack bench: throughput of every render backend and of the OpenCV
// baseline, in one run, on the same scene (bench.hpp): the hydrogel gripper
// ~114 px across at 256x256. Hypotheses per second for batches of --batch
// (32), and frames per second of the paper's PSO (N = 32, G = 25) per
// backend.
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

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
  std::string note;  // why there is no value
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
  const int all = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  std::string gripper_source;
  const gtrack::ArticulatedModel model = gtrack::load_bench_gripper(common.plugin_paths, gripper_source);
  const gtrack::BenchScene scene = gtrack::make_bench_scene(model, kSide, kGripperPx);
  gtrack::logger().info("bench: {} at {}x{}, {:.0f} px across, {} s per measurement", gripper_source, kSide, kSide,
                        kGripperPx, seconds);

  auto hypotheses = [&](gtrack::Renderer& r) {
    return gtrack::measure_hypotheses(r, scene, seconds, batch).per_second;
  };
  auto frames = [&](gtrack::Renderer& r) { return gtrack::measure_pso_frames(r, scene, seconds).per_second; };

  Measured cpu1, cpu_all, cpu_frames, base1, base_all, gl, gl_frames;
  {
    std::string why;
    auto r = try_make(gtrack::make_cpu_renderer, 1, why);
    cpu1.value = hypotheses(*r);
    r = try_make(gtrack::make_cpu_renderer, all, why);
    cpu_all.value = hypotheses(*r);
    cpu_frames.value = frames(*r);
  }
  {
    std::string why;
    auto r = try_make(gtrack::make_opencv_baseline, 1, why);
    base1.value = hypotheses(*r);
    r = try_make(gtrack::make_opencv_baseline, all, why);
    base_all.value = hypotheses(*r);
  }
  {
    std::string why;
    if (auto r = try_make(gtrack::make_gl_renderer, 0, why)) {
      try {
        gl.value = hypotheses(*r);
        gl_frames.value = frames(*r);
      } catch (const gtrack::Error& e) {
        why = e.what();
      }
    }
    gl.note = gl_frames.note = why;
  }
  const double ratio_all = *cpu_all.value / *base_all.value;
  const double ratio_one = *cpu1.value / *base1.value;

  if (json) {
    std::cout << "{\"hypotheses_per_s\": {\"cpu\": " << json_number(cpu_all.value)
              << ", \"gl\": " << json_number(gl.value) << ", \"opencv_baseline\": " << json_number(base_all.value)
              << "},\n \"frames_per_s\": {\"cpu\": " << json_number(cpu_frames.value)
              << ", \"gl\": " << json_number(gl_frames.value) << "},\n"
              << " \"frames_per_s_is\": \"full PSO search of one frame: N=32 particles, G=25 generations, cost "
                 "of eq. (1); no segmentation or I/O\",\n"
              << " \"cpu_hypotheses_per_s_by_threads\": {\"1\": " << json_number(cpu1.value) << ", \"" << all
              << "\": " << json_number(cpu_all.value) << "},\n"
              << " \"opencv_baseline_hypotheses_per_s_by_threads\": {\"1\": " << json_number(base1.value) << ", \""
              << all << "\": " << json_number(base_all.value) << "},\n"
              << " \"cpu_over_opencv_baseline\": {\"1\": " << json_number(ratio_one) << ", \"" << all
              << "\": " << json_number(ratio_all) << "},\n"
              << " \"threads\": " << all << ", \"batch\": " << batch << ", \"render_size\": [" << kSide << ", " << kSide
              << "], \"gripper_px\": " << kGripperPx << ", \"gripper\": " << gtrack::json_string(gripper_source)
              << ", \"seconds_per_measurement\": " << seconds;
    if (!gl.value) std::cout << ",\n \"gl_unavailable\": " << gtrack::json_string(gl.note);
    std::cout << "}\n";
    return 0;
  }

  std::printf("gtrack bench: %s, %dx%d render, gripper ~%.0f px across, batches of %d\n\n", gripper_source.c_str(),
              kSide, kSide, kGripperPx, batch);
  std::printf("%-18s %12s %14s %16s\n", "backend", "threads", "hypotheses/s", "PSO frames/s");
  std::printf("%-18s %12d %14s %16s\n", "cpu", 1, human(cpu1.value).c_str(), "");
  std::printf("%-18s %12d %14s %16s\n", "cpu", all, human(cpu_all.value).c_str(), human(cpu_frames.value).c_str());
  std::printf("%-18s %12s %14s %16s\n", "gl", "", human(gl.value).c_str(), human(gl_frames.value).c_str());
  std::printf("%-18s %12d %14s %16s\n", "opencv_baseline", 1, human(base1.value).c_str(), "");
  std::printf("%-18s %12d %14s %16s\n", "opencv_baseline", all, human(base_all.value).c_str(), "");
  std::printf("\ncpu / opencv_baseline: %.1fx (1 thread), %.1fx (%d threads)\n", ratio_one, ratio_all, all);
  std::printf("PSO frame = N=32 particles x G=25 generations with the cost of eq. (1); no segmentation or I/O\n");
  if (!gl.value) std::printf("gl: not measured: %s\n", gl.note.c_str());
  return 0;
}

}  // namespace

GTRACK_COMMAND("bench", "throughput of every render backend and of the OpenCV baseline, in one run",
               [](po::options_description& d) {
                 d.add_options()("json", "print one JSON object instead of a table")(
                     "seconds", po::value<double>()->default_value(1.0), "time spent on each measurement")(
                     "batch", po::value<int>()->default_value(32),
                     "hypotheses per batch for hypotheses/s (a swarm's N; PSO frames/s keep N = 32)");
               },
               run_bench, {})
