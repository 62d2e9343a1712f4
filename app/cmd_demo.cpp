// gtrack demo: synthesise a short sequence with the built-in config, track
// it and score it; the README's first command.
#include <fstream>
#include <iomanip>
#include <iostream>

#include "command.hpp"
#include "gtrack/error.hpp"
#include "gtrack/evaluation.hpp"
#include "gtrack/plugin_loader.hpp"
#include "gtrack/synth.hpp"
#include "gtrack/synthetic_benchmark.hpp"
#include "gtrack/text_file.hpp"
#include "gtrack/tracker.hpp"
#include "gtrack/two_pass.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

int run_demo(const gtrack::cli::CommonOptions& common, const po::variables_map& vm) {
  const fs::path out = gtrack::cli::out_folder(vm);
  gtrack::SynthOptions so;
  so.frames = vm["frames"].as<int>();
  so.seed = gtrack::cli::seed_option(vm);
  so.preset = vm["preset"].as<std::string>();
  if (so.frames < 2 || so.frames > gtrack::cli::kMaxSynthFrames) {
    throw gtrack::cli::UsageError("--frames must be from 2 to " + std::to_string(gtrack::cli::kMaxSynthFrames));
  }
  const gtrack::SynthPreset& preset = gtrack::synth_preset(so.preset);
  const fs::path config = gtrack::data_dir() / "configs" / preset.config;
  if (!fs::is_regular_file(config)) {
    throw gtrack::InputError("built-in config " + config.string() + " not found (is the build or install complete?)");
  }

  gtrack::SetupOptions opts;
  opts.plugin_paths = common.plugin_paths;
  const fs::path seq = out / "sequence";
  std::cout << "1/3 synthesising " << so.frames << " frames (" << preset.summary << ") ...\n" << std::flush;
  const auto synth = gtrack::write_synthetic_sequence(gtrack::load_setup(config, opts), so, seq);
  std::cout << "    " << synth.frames << " frames in " << std::fixed << std::setprecision(1) << synth.seconds
            << " s; " << synth.occluded_frames << " occluded (max " << std::setprecision(0)
            << 100 * synth.max_occlusion << "% of the shape), " << synth.out_of_view_frames << " out of view\n";

  std::cout << "2/3 tracking, then tracking the recording again backwards ...\n" << std::flush;
  gtrack::Setup setup = gtrack::load_synthetic_setup(seq, common.plugin_paths);
  const gtrack::EngineConfig cfg = gtrack::engine_config(setup);
  gtrack::check_root_keys(setup);
  gtrack::TrackOptions to;
  to.input = (seq / "frames").string();
  to.stimulus_csv = seq / "stimulus.csv";
  to.out_dir = out / "track";
  std::vector<gtrack::Estimate> forward;
  to.on_frame = [&forward](const gtrack::Estimate& e) { forward.push_back(e); };
  const gtrack::TrackSummary track = gtrack::track_sequence(setup, cfg, to);
  const gtrack::TwoPassSummary both = gtrack::two_pass(setup, cfg, to, forward);

  std::cout << "3/3 evaluating ...\n";
  const auto truth = gtrack::read_truth_table(seq / "ground_truth.csv");
  const auto estimates = gtrack::read_pose_table(to.out_dir / "estimates.csv");
  gtrack::EvalOptions judged;
  judged.off_track_in_plane = gtrack::cli::images_a_slab(*setup.sensor);
  const auto ev = gtrack::evaluate(setup.model(), truth, estimates, judged, setup.sensor.get());
  const fs::path two_pass_csv = to.out_dir / "two_pass" / "estimates.csv";
  const auto ev2 =
      gtrack::evaluate(setup.model(), truth, gtrack::read_pose_table(two_pass_csv), judged, setup.sensor.get());
  gtrack::write_text_file(out / "evaluation.json", gtrack::evaluation_json(ev));
  gtrack::write_frame_errors(out / "frame_errors.csv", ev);

  const auto& e = ev.in_view;
  // Beside each figure, the paper's (the hydrogel under the microscope) or
  // the target of the preset's setup (docs/RESULTS.md).
  struct Beside {
    const char *position, *orientation, *joints;
  };
  const Beside beside = so.preset == "microscope" || so.preset == "brightfield" ? Beside{"(paper: 25 +- 7 um)", "(paper: 1.7 +- 1.3 deg)",
                                                           "(paper: 1.4 +- 0.95 deg)"}
                        : so.preset.rfind("metallic", 0) == 0
                            ? Beside{"(target: <= 10 um)", "(target: <= 2.5 deg)", "(target: <= 2.5 deg)"}
                        : so.preset == "ultrasound" ? Beside{"(target: <= 180 um)", "", ""}
                                                    : Beside{"", "", ""};
  const auto after = [](const char* text) { return *text ? std::string("  ") + text : std::string(); };
  const bool slab = gtrack::cli::images_a_slab(*setup.sensor);
  std::cout << std::setprecision(1) << "\nresult over " << ev.evaluated_frames << " in-view frames ("
            << ev.lost_frames << " lost, " << ev.out_of_view_frames << " out of view), N=" << cfg.pso.particles
            << " G=" << cfg.pso.generations << ", " << track.renderer << " renderer, "
            << (track.mean_ms > 0 ? 1000.0 / track.mean_ms : 0.0)
            << " frames/s of tracking (segmentation and search, sharing the cores with the reading and drawing "
               "threads; "
            << (track.wall_s > 0 ? track.frames / track.wall_s : 0.0) << " frames/s end to end):\n"
            << (slab ? "  in the imaging plane " : "  position in-plane ") << e.position_inplane_um.mean << " +- "
            << e.position_inplane_um.std << " um " << after(beside.position) << "\n"
            << (slab ? "  across the plane     " : "  depth             ") << e.depth_um.mean << " +- "
            << e.depth_um.std << " um\n"
            << "  orientation       " << std::setprecision(2) << e.orientation_deg.mean << " +- "
            << e.orientation_deg.std << " deg" << after(beside.orientation) << "\n"
            << "  joints            " << e.joint_deg.mean << " +- " << e.joint_deg.std << " deg"
            << after(beside.joints) << "\n"
            << std::setprecision(1) << "  phalanx endpoints " << e.endpoint_um.mean << " +- " << e.endpoint_um.std
            << " um\n"
            << "two passes (offline: the recording also tracked backwards, " << both.from_backward << " of "
            << both.frames << " frames taken from the backward track, " << gtrack::smoothing_report(both) << "; "
            << both.wall_s << " s):\n"
            << (slab ? "  in the imaging plane " : "  position in-plane ") << ev2.in_view.position_inplane_um.mean
            << " um, orientation "
            << std::setprecision(2) << ev2.in_view.orientation_deg.mean << " deg, joints "
            << ev2.in_view.joint_deg.mean << " deg\n\n"
            << "frames and ground truth: " << seq.string() << "\n"
            << "overlay video:           "
            << (track.overlay_file.empty() ? std::string("(none written)") : track.overlay_file.string()) << "\n"
            << "estimates:               " << (to.out_dir / "estimates.csv").string() << " and "
            << (to.out_dir / "estimates.jsonl").string() << "\n"
            << "two-pass estimates:      " << two_pass_csv.string() << "\n"
            << "evaluation:              " << (out / "evaluation.json").string() << " and "
            << (out / "frame_errors.csv").string() << "\n";
  return 0;
}

}  // namespace

GTRACK_COMMAND(
    "demo", "synthesise a short sequence with the built-in config, track it and evaluate it",
    [](po::options_description& d) {
      d.add_options()("out,o", po::value<std::string>()->default_value("gtrack_demo"), "folder to write")(
          "frames,n", po::value<int>()->default_value(60), "frames to synthesise and track")(
          "seed,s", po::value<std::string>()->default_value("1"), "random seed of the sequence")(
          "preset", po::value<std::string>()->default_value("microscope"),
          ("synthetic setup, one of " + gtrack::synth_preset_names()).c_str());
    },
    run_demo)
