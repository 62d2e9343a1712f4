// gtrack sweep: the paper's Fig. 6 on synthetic sequences.
//   6a: phalanx-endpoint error against particles N x generations G;
//   6b: joint error when every hinge deviates from its finger's value by
//       Gaussian noise of sd sigma (the model assumes they are equal).
// Writes fig6a.csv / fig6b.csv and plots of them drawn with OpenCV.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <optional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "command.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/plugin_loader.hpp"
#include "gtrack/synth.hpp"
#include "gtrack/synthetic_benchmark.hpp"
#include "gtrack/text_file.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

// "8,16,32": each item a whole decimal number (spaces around it allowed);
// "8;16", "8abc" or "0x5" are refused, not read as their first number.
std::vector<double> parse_list(const std::string& text, const char* option) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const size_t first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
    const std::string trimmed = first == std::string::npos ? std::string() : item.substr(first, last - first + 1);
    double value = 0;
    const char* begin = trimmed.data() + (trimmed.rfind('+', 0) == 0 ? 1 : 0);
    const char* end = trimmed.data() + trimmed.size();
    const auto [ptr, ec] = std::from_chars(begin, end, value, std::chars_format::general);
    if (trimmed.empty() || ec != std::errc() || ptr != end || !std::isfinite(value)) {
      throw gtrack::cli::UsageError(std::string("--") + option + ": '" + item +
                                    "' is not a number (expected numbers separated by commas, e.g. 8,16,32)");
    }
    out.push_back(value);
  }
  if (out.empty()) throw gtrack::cli::UsageError(std::string("--") + option + " needs at least one value");
  return out;
}

struct Series {
  std::string label;
  std::vector<double> x, y, err;
};

// A line plot with error bars: enough for Fig. 6 without a plotting library.
void plot(const fs::path& file, const std::string& title, const std::string& xlabel, const std::string& ylabel,
          const std::vector<Series>& series, const std::vector<double>& xticks, bool log2x) {
  const int W = 760, H = 520, L = 80, R = 170, T = 50, B = 70;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  auto fx = [&](double x) { return log2x ? std::log2(x) : x; };
  double x0 = 1e300, x1 = -1e300, y1 = 0;
  for (double t : xticks) x0 = std::min(x0, fx(t)), x1 = std::max(x1, fx(t));
  for (const auto& s : series)
    for (size_t i = 0; i < s.y.size(); ++i) y1 = std::max(y1, s.y[i] + s.err[i]);
  if (x1 <= x0) x1 = x0 + 1;
  y1 = y1 > 0 ? y1 * 1.1 : 1;
  auto px = [&](double x) { return cv::Point(static_cast<int>(L + (fx(x) - x0) / (x1 - x0) * (W - L - R)), 0); };
  auto py = [&](double y) { return static_cast<int>(H - B - y / y1 * (H - T - B)); };
  const cv::Scalar black(0, 0, 0), grey(210, 210, 210);
  for (int k = 0; k <= 5; ++k) {
    const double y = y1 * k / 5;
    cv::line(img, {L, py(y)}, {W - R, py(y)}, grey, 1);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", y);
    cv::putText(img, buf, {8, py(y) + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
  }
  for (double t : xticks) {
    const int x = px(t).x;
    cv::line(img, {x, H - B}, {x, H - B + 6}, black, 1);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", t);
    cv::putText(img, buf, {x - 10, H - B + 24}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
  }
  cv::rectangle(img, {L, T}, {W - R, H - B}, black, 1);
  cv::putText(img, title, {L + 90, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6, black, 1, cv::LINE_AA);
  cv::putText(img, xlabel, {L + (W - L - R) / 2 - 60, H - 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black, 1, cv::LINE_AA);
  cv::putText(img, ylabel, {8, T - 6}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black, 1, cv::LINE_AA);
  const cv::Scalar colours[] = {{200, 80, 30}, {40, 160, 40}, {30, 30, 220}, {160, 40, 160}, {20, 150, 200}};
  for (size_t s = 0; s < series.size(); ++s) {
    const cv::Scalar c = colours[s % 5];
    std::optional<cv::Point> prev;
    for (size_t i = 0; i < series[s].x.size(); ++i) {
      // A cell without a frame to judge (all lost) has no point, and the
      // line does not pass through it.
      if (!std::isfinite(series[s].y[i])) {
        prev.reset();
        continue;
      }
      const cv::Point p(px(series[s].x[i]).x, py(series[s].y[i]));
      cv::line(img, {p.x, py(std::max(0.0, series[s].y[i] - series[s].err[i]))},
               {p.x, py(series[s].y[i] + series[s].err[i])}, c, 1, cv::LINE_AA);
      cv::circle(img, p, 4, c, cv::FILLED, cv::LINE_AA);
      if (prev) cv::line(img, *prev, p, c, 2, cv::LINE_AA);
      prev = p;
    }
    cv::line(img, {W - R + 15, T + 20 + 22 * int(s)}, {W - R + 40, T + 20 + 22 * int(s)}, c, 2, cv::LINE_AA);
    cv::putText(img, series[s].label, {W - R + 48, T + 25 + 22 * int(s)}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black, 1,
                cv::LINE_AA);
  }
  if (!cv::imwrite(file.string(), img)) throw gtrack::InputError(file.string() + ": cannot write");
}

struct Context {
  gtrack::cli::CommonOptions common;
  fs::path config, out;
  std::vector<gtrack::NamedFile> named_files;  // the files the config names (a gripper's model file, ...)
  gtrack::SynthOptions synth;
  int sequences = 1;
};

// A hash of a file's bytes ("missing" when it cannot be read).
std::string content_hash(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return "missing";
  std::ostringstream text;
  text << in.rdbuf();
  return std::to_string(std::hash<std::string>{}(text.str()));
}

// What a cached sequence was made from: the config's text, the files it
// names (a gripper's model file, ...) and the synth options. A sequence is
// reused only when they are the same, so that a sweep run again in the same
// --out with another config, model, preset or length does not score the old
// sequences.
std::string sequence_recipe(const Context& c, std::uint64_t seed, double noise) {
  char line[256];
  std::snprintf(line, sizeof line, "frames %d\npreset %s\nseed %llu\nnoise %.17g\nocclusion_scale %.17g\n",
                c.synth.frames, c.synth.preset.c_str(), static_cast<unsigned long long>(seed), noise,
                c.synth.occlusion_scale);
  std::string recipe = "config " + fs::absolute(c.config).string() + "\nconfig_hash " + content_hash(c.config) + "\n";
  for (const gtrack::NamedFile& f : c.named_files) {
    recipe += "file " + f.dotted() + " " + fs::absolute(f.path).string() + " " + content_hash(f.path) + "\n";
  }
  return recipe + line;
}

fs::path make_sequence(const Context& c, std::uint64_t seed, double noise) {
  char name[64];
  std::snprintf(name, sizeof name, "seq_seed%llu_noise%g", static_cast<unsigned long long>(seed), noise);
  const fs::path dir = c.out / "sequences" / name;
  const fs::path stamp = dir / "made_from.txt";
  const std::string recipe = sequence_recipe(c, seed, noise);
  if (fs::exists(dir / "ground_truth.csv") && fs::exists(dir / "sequence.toml") && fs::exists(stamp)) {
    std::ifstream in(stamp, std::ios::binary);
    std::ostringstream had;
    had << in.rdbuf();
    if (had.str() == recipe) return dir;  // reuse
  }
  if (fs::exists(dir)) {
    gtrack::logger().info("sweep: {} was made from other settings; making it again", dir.string());
    fs::remove_all(dir);
  }
  gtrack::SynthOptions o = c.synth;
  o.seed = seed;
  o.joint_noise_deg = noise;
  gtrack::SetupOptions so;
  so.plugin_paths = c.common.plugin_paths;
  gtrack::write_synthetic_sequence(gtrack::load_setup(c.config, so), o, dir);
  gtrack::write_text_file(stamp, recipe);
  return dir;
}

struct Cell {
  double endpoint = 0, endpoint_sd = 0, inplane = 0, depth = 0, orientation = 0, joints = 0, joints_sd = 0, fps = 0;
  int lost = 0, frames = 0;
  int judged = 0;  // in-view frames with an estimate, whose errors these are
};

Cell run_cell(const Context& c, double noise, int particles, int generations) {
  Cell cell;
  // Each error's frames pooled over the sequences (gtrack::pooled).
  std::vector<gtrack::ErrorStats> endpoint, inplane, depth, orientation, joints;
  for (int s = 0; s < c.sequences; ++s) {
    const fs::path dir = make_sequence(c, c.synth.seed + s, noise);
    const gtrack::Setup setup = gtrack::load_synthetic_setup(dir, c.common.plugin_paths);
    gtrack::EngineConfig cfg = gtrack::engine_config(setup);
    cfg.pso.particles = particles;
    cfg.pso.generations = generations;
    cfg.tracker.overlay = false;
    const auto run = gtrack::run_synthetic_benchmark(setup, cfg, dir);
    const auto& e = run.evaluation.in_view;
    endpoint.push_back(e.endpoint_um);
    inplane.push_back(e.position_inplane_um);
    depth.push_back(e.depth_um);
    orientation.push_back(e.orientation_deg);
    joints.push_back(e.joint_deg);
    cell.fps += run.tracker_fps / c.sequences;
    cell.lost += run.evaluation.lost_in_view_frames;
    cell.frames += run.frames;
  }
  // Errors of no frame at all (every one lost or out of view) are NaN, not
  // 0: written "nan" and left off the plot, never the grid's best cell.
  const auto none = std::numeric_limits<double>::quiet_NaN();
  const auto mean = [&](const gtrack::ErrorStats& e) { return e.count > 0 ? e.mean : none; };
  const auto sd = [&](const gtrack::ErrorStats& e) { return e.count > 0 ? e.std : none; };
  const gtrack::ErrorStats ends = gtrack::pooled(endpoint), folds = gtrack::pooled(joints);
  cell.judged = ends.count;
  cell.endpoint = mean(ends);
  cell.endpoint_sd = sd(ends);
  cell.inplane = mean(gtrack::pooled(inplane));
  cell.depth = mean(gtrack::pooled(depth));
  cell.orientation = mean(gtrack::pooled(orientation));
  cell.joints = mean(folds);
  cell.joints_sd = sd(folds);
  return cell;
}

// A figure's CSV, each row on disk as soon as its cell is measured.
class FigureCsv {
 public:
  FigureCsv(fs::path file, const std::string& header) : file_(std::move(file)), out_(file_) {
    if (!out_) fail("cannot open for writing");
    out_ << header << "\n";
    flush();
  }
  void row(const std::string& head, const Cell& c) {
    out_ << head << "," << c.frames << "," << c.endpoint << "," << c.endpoint_sd << "," << c.inplane << "," << c.depth
         << "," << c.orientation << "," << c.joints << "," << c.joints_sd << "," << c.lost << "," << c.fps << "\n";
    flush();
  }

 private:
  void flush() {
    out_.flush();
    if (!out_) fail("cannot write (is the disk full?)");
  }
  [[noreturn]] void fail(const std::string& what) const {
    std::error_code ec;
    throw gtrack::InputError(file_.string() + ": " + what +
                             (fs::is_directory(file_, ec) ? " (it is a folder; expected a file)" : ""));
  }
  fs::path file_;
  std::ofstream out_;
};

const char* kColumns =
    "frames,endpoint_um,endpoint_um_sd,inplane_um,depth_um,orientation_deg,joint_deg,joint_deg_sd,lost_in_view,"
    "tracker_fps";

int run_sweep(const gtrack::cli::CommonOptions& common, const po::variables_map& vm) {
  Context c;
  c.common = common;
  c.out = gtrack::cli::out_folder(vm);
  c.synth.frames = vm["frames"].as<int>();
  c.synth.seed = gtrack::cli::seed_option(vm);
  c.synth.preset = vm["preset"].as<std::string>();
  c.sequences = vm["sequences"].as<int>();
  if (c.synth.frames < 2 || c.synth.frames > gtrack::cli::kMaxSynthFrames) {
    throw gtrack::cli::UsageError("--frames must be from 2 to " + std::to_string(gtrack::cli::kMaxSynthFrames));
  }
  if (c.sequences < 1 || c.sequences > 1000) throw gtrack::cli::UsageError("--sequences must be from 1 to 1000");
  c.config = vm.count("config") ? fs::path(vm["config"].as<std::string>())
                                : gtrack::data_dir() / "configs" / gtrack::synth_preset(c.synth.preset).config;
  {
    // Each sequence reads the config again: a pipe would be empty the second time.
    std::error_code ec;
    if (vm.count("config") && fs::exists(c.config, ec) && !fs::is_regular_file(c.config, ec) &&
        !fs::is_directory(c.config, ec)) {
      throw gtrack::cli::UsageError("--config " + c.config.string() +
                                    ": a pipe; sweep reads its config once per sequence, so give a file");
    }
  }
  const auto particles = parse_list(vm["particles"].as<std::string>(), "particles");
  const auto generations = parse_list(vm["generations"].as<std::string>(), "generations");
  const auto sigmas = parse_list(vm["sigmas"].as<std::string>(), "sigmas");
  const std::string which = vm["figure"].as<std::string>();
  if (which != "6a" && which != "6b" && which != "both") throw gtrack::cli::UsageError("--figure: 6a, 6b or both");
  // Every value is checked before the first sequence is made.
  const auto check = [](const std::vector<double>& values, double lo, double hi, bool whole, const char* option,
                        const char* what) {
    for (double v : values) {
      if (!(v >= lo && v <= hi) || (whole && v != std::floor(v))) {
        std::ostringstream m;
        m << "--" << option << ": expected " << what << " from " << lo << " to " << hi << ", got " << v;
        throw gtrack::cli::UsageError(m.str());
      }
    }
  };
  // The bounds of [pso] particles and generations.
  check(particles, 2, 65536, true, "particles", "whole numbers");
  check(generations, 1, 65536, true, "generations", "whole numbers");
  check(sigmas, 0, 90, false, "sigmas", "degrees");
  check({static_cast<double>(vm["fig6b-particles"].as<int>())}, 2, 65536, true, "fig6b-particles", "a whole number");
  check({static_cast<double>(vm["fig6b-generations"].as<int>())}, 1, 65536, true, "fig6b-generations",
        "a whole number");
  // The config is checked, as track checks it, before anything is made:
  // its errors name the user's file, not a sequence made from it.
  {
    gtrack::SetupOptions so;
    so.plugin_paths = c.common.plugin_paths;
    const gtrack::Setup setup = gtrack::load_setup(c.config, so);
    const gtrack::ObservationConfig bounds = gtrack::engine_config(setup).observation;
    gtrack::check_root_keys(setup);
    c.named_files = setup.root.named_files();
    // A config without --preset: sequences its bounds can track, as synth makes.
    c.synth.preset = gtrack::cli::synth_preset_for(vm, c.config, setup, bounds);
  }
  gtrack::cli::make_output_folder(c.out, "out");

  if (which != "6b") {
    FigureCsv csv(c.out / "fig6a.csv", std::string("particles,generations,") + kColumns);
    std::vector<Series> series;
    for (double g : generations) {
      Series s;
      s.label = "G = " + std::to_string(static_cast<int>(g));
      for (double n : particles) {
        const Cell cell = run_cell(c, 0, static_cast<int>(n), static_cast<int>(g));
        csv.row(std::to_string(int(n)) + "," + std::to_string(int(g)), cell);
        if (cell.judged == 0) {
          std::printf("6a  N=%3d G=%3d  no frame to judge: lost %d of %d  %.1f frames/s\n", int(n), int(g), cell.lost,
                      cell.frames, cell.fps);
        } else {
          std::printf("6a  N=%3d G=%3d  endpoints %7.1f um  in-plane %6.1f um  orientation %5.2f deg  joints %5.2f "
                      "deg  lost %d  %.1f frames/s\n",
                      int(n), int(g), cell.endpoint, cell.inplane, cell.orientation, cell.joints, cell.lost, cell.fps);
        }
        std::fflush(stdout);
        s.x.push_back(n);
        s.y.push_back(cell.endpoint);
        s.err.push_back(0);
      }
      series.push_back(s);
    }
    plot(c.out / "fig6a.png", "Fig. 6a: phalanx endpoint error vs particles", "particles N", "error (um)", series,
         particles, true);
  }
  if (which != "6a") {
    const int n = vm["fig6b-particles"].as<int>(), g = vm["fig6b-generations"].as<int>();
    FigureCsv csv(c.out / "fig6b.csv", std::string("sigma_deg,particles,generations,") + kColumns);
    Series s;
    s.label = "N=" + std::to_string(n) + " G=" + std::to_string(g);
    for (double sigma : sigmas) {
      const Cell cell = run_cell(c, sigma, n, g);
      char head[64];
      std::snprintf(head, sizeof head, "%g,%d,%d", sigma, n, g);
      csv.row(head, cell);
      if (cell.judged == 0) {
        std::printf("6b  sigma=%.2f deg  no frame to judge: lost %d of %d\n", sigma, cell.lost, cell.frames);
      } else {
        std::printf("6b  sigma=%.2f deg  joints %5.2f +- %5.2f deg  endpoints %7.1f um  lost %d\n", sigma, cell.joints,
                    cell.joints_sd, cell.endpoint, cell.lost);
      }
      std::fflush(stdout);
      s.x.push_back(sigma);
      s.y.push_back(cell.joints);
      s.err.push_back(cell.joints_sd);
    }
    plot(c.out / "fig6b.png", "Fig. 6b: joint error vs per-hinge noise", "noise sigma (deg)", "joint error (deg)",
         {s}, sigmas, false);
  }
  std::cout << "results: " << c.out.string() << "/"
            << (which == "6a" ? "fig6a.csv, fig6a.png" : which == "6b" ? "fig6b.csv, fig6b.png"
                                                                       : "fig6a.csv, fig6a.png, fig6b.csv, fig6b.png")
            << "\n";
  return 0;
}

}  // namespace

GTRACK_COMMAND(
    "sweep", "paper Fig. 6: error vs particles x generations (6a) and vs per-hinge joint noise (6b)",
    [](po::options_description& d) {
      d.add_options()("out,o", po::value<std::string>()->default_value("gtrack_sweep"), "folder to write")(
          "config,c", po::value<std::string>(), "config (default: the preset's built-in config)")(
          "preset", po::value<std::string>()->default_value("microscope"),
          ("synthetic setup, one of " + gtrack::synth_preset_names() +
           "; with --config and no --preset, one whose frames the config can track, as gtrack synth takes it")
              .c_str())(
          "frames,n", po::value<int>()->default_value(60), "frames per sequence (paper: 5614 frames in all)")(
          "sequences", po::value<int>()->default_value(1), "sequences per cell, seeds seed, seed+1, ...")(
          "seed,s", po::value<std::string>()->default_value("1"), "first seed")(
          "particles", po::value<std::string>()->default_value("8,16,32,64"), "values of N (6a)")(
          "generations", po::value<std::string>()->default_value("5,10,25,50"), "values of G (6a)")(
          "sigmas", po::value<std::string>()->default_value("0,0.5,1,1.5,2"), "per-hinge noise sd, deg (6b)")(
          "fig6b-particles", po::value<int>()->default_value(32), "N for 6b")(
          "fig6b-generations", po::value<int>()->default_value(25), "G for 6b")(
          "figure", po::value<std::string>()->default_value("both"), "6a, 6b or both");
    },
    run_sweep)
