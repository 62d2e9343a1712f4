// gtrack synth: a synthetic sequence with ground truth (paper Section 5.1).
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <iomanip>
#include <iostream>

#include "command.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/plugin_loader.hpp"
#include "gtrack/synth.hpp"

namespace po = boost::program_options;

namespace {

int run_synth(const gtrack::cli::CommonOptions& common, const po::variables_map& vm) {
  gtrack::SynthOptions o;
  o.preset = vm["preset"].as<std::string>();
  o.frames = vm["frames"].as<int>();
  o.seed = gtrack::cli::seed_option(vm);
  o.joint_noise_deg = vm["joint-noise"].as<double>();
  o.occlusion_scale = vm["occlusion-scale"].as<double>();
  o.threads = vm["threads"].as<int>();
  if (vm.count("stimulus")) o.stimulus_log = vm["stimulus"].as<std::string>();
  if (vm.count("stimulus-column")) {
    if (!o.stimulus_log) throw gtrack::cli::UsageError("--stimulus-column needs --stimulus");
    o.stimulus_column = vm["stimulus-column"].as<std::string>();
  }
  if (vm.count("stimulus-offset")) {
    if (!o.stimulus_log) throw gtrack::cli::UsageError("--stimulus-offset needs --stimulus");
    o.stimulus_offset_s = vm["stimulus-offset"].as<double>();
    if (!std::isfinite(o.stimulus_offset_s)) {
      throw gtrack::cli::UsageError("--stimulus-offset: expected a finite number of seconds");
    }
  }
  if (o.threads < 0) throw gtrack::cli::UsageError("--threads must be 0 (all cores) or more");
  if (o.frames < 1 || o.frames > gtrack::cli::kMaxSynthFrames) {
    throw gtrack::cli::UsageError("--frames must be from 1 to " + std::to_string(gtrack::cli::kMaxSynthFrames));
  }
  if (!(o.joint_noise_deg >= 0 && o.joint_noise_deg <= 90)) {
    throw gtrack::cli::UsageError("--joint-noise must be a number of degrees in [0, 90]");
  }
  if (!(o.occlusion_scale >= 0 && o.occlusion_scale <= 1)) {
    throw gtrack::cli::UsageError("--occlusion-scale must be in [0, 1]");
  }
  const std::filesystem::path config = vm.count("config") ? std::filesystem::path(vm["config"].as<std::string>())
                                                          : gtrack::data_dir() / "configs" /
                                                                gtrack::synth_preset(o.preset).config;
  gtrack::SetupOptions so;
  so.plugin_paths = common.plugin_paths;
  gtrack::Setup setup = gtrack::load_setup(config, so);
  // Checked as track checks it: sequence.toml carries the engine's tables,
  // and its `track it:` line must not fail on them.
  const gtrack::ObservationConfig bounds = gtrack::engine_config(setup).observation;
  gtrack::check_root_keys(setup);
  o.preset = gtrack::cli::synth_preset_for(vm, config, setup, bounds);
  const std::filesystem::path out = gtrack::cli::out_folder(vm);
  const gtrack::SynthSummary s = gtrack::write_synthetic_sequence(setup, o, out);
  std::string unit;
  if (setup.stimulus && !setup.stimulus->reading_unit().empty()) unit = fmt::format(" {}", setup.stimulus->reading_unit());
  std::cout << std::fixed << std::setprecision(1) << "synthetic sequence: " << s.frames << " frames (preset "
            << o.preset << ", seed " << o.seed << ") in " << s.seconds << " s -> " << out.string() << "\n"
            << "  occluded frames: " << s.occluded_frames << " (" << 100.0 * s.occluded_frames / s.frames
            << "%), mean " << 100 * s.mean_occlusion << "% of the shape, max " << 100 * s.max_occlusion << "%\n"
            << "  partly out of view (10-99% imaged: inside the image, and a slice's slab): " << s.partly_out_frames
            << ", out of view (<10% imaged): "
            << s.out_of_view_frames << "\n"
            << std::defaultfloat << std::setprecision(6)  // readings in any unit: significant digits
            << "  stimulus: " << s.stimulus_min << " to " << s.stimulus_max << unit
            << (o.stimulus_log ? " (from " + o.stimulus_log->string() + ")"
                               : " (the profile's range: " + fmt::format("{:g} to {:g}", s.stimulus_low, s.stimulus_high) +
                                     unit + ")")
            << ", " << std::fixed << std::setprecision(1)
            << "joints: " << s.joint_min_deg << " to " << s.joint_max_deg << " deg\n";
  // From 2.5 s on, a sequence holds a whole heating and cooling cycle.
  if (o.stimulus_log && s.joint_max_deg - s.joint_min_deg < 1) {
    std::cout << "  note: the joints do not fold: the log's readings never cross the plugin's fold band\n";
  } else if (s.duration_s >= 2.5 && s.joint_max_deg - s.joint_min_deg < 1) {
    std::cout << "  note: the joints do not fold: the stimulus never crosses the plugin's fold band; set "
                 "stimulus_low and stimulus_high in the config's [synth] table\n";
  }
  std::cout << "  track it: gtrack track --config " << s.sequence_config.string() << " --input "
            << (out / "frames").string() << " --stimulus " << (out / "stimulus.csv").string() << " --out "
            << (out / "track").string() << "\n";
  return 0;
}

}  // namespace

GTRACK_COMMAND(
    "synth", "render a synthetic sequence with ground truth (frames, stimulus.csv, ground_truth.csv, sequence.toml)",
    [](po::options_description& d) {
      d.add_options()("config,c", po::value<std::string>(),
                      "TOML config naming sensor, gripper and stimulus (default: the preset's config)")(
          "out,o", po::value<std::string>()->required(), "folder to write")(
          "frames,n", po::value<int>()->default_value(300), "number of frames")(
          "seed,s", po::value<std::string>()->default_value("1"), "random seed: same seed, same sequence")(
          "preset", po::value<std::string>()->default_value("microscope"),
          ("setup: motion, look and noise; one of " + gtrack::synth_preset_names() +
           ". With --config and no --preset: the preset whose config has the config's file name, else the one "
           "whose config names the same gripper plugin, else the first whose look the config's bounds find "
           "(its gripper within them, its background not): microscope in colour; ultrasound or brightfield for "
           "grey levels")
              .c_str())(
          "joint-noise", po::value<double>()->default_value(0.0),
          "sd (deg) of per-hinge deviation from each finger's joint value (paper Fig. 6b)")(
          "occlusion-scale", po::value<double>()->default_value(1.0),
          "multiplies each occluder's share of the shape, in [0, 1]; 0 = no occluders, the rest of the sequence "
          "unchanged")(
          "threads", po::value<int>()->default_value(0), "frames drawn in parallel (0 = all cores)")(
          "stimulus", po::value<std::string>(),
          "a lab's stimulus log (frame,value or time_s,value) that drives the material instead of the preset's "
          "profile")(
          "stimulus-column", po::value<std::string>(), "of a log with several named columns, the readings' one")(
          "stimulus-offset", po::value<double>(),
          "SECONDS: a time_s log on another clock: its time at the sequence's first frame, subtracted from its "
          "times");
    },
    run_synth)
