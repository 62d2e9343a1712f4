// Synthetic sequences: the drawn gripper is the model the tracker renders,
// segmented by the default observation settings; plans are deterministic and
// have the occlusions, exits and folding the benchmark promises.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <opencv2/imgproc.hpp>

#include "gtrack/engine_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/model.hpp"
#include "gtrack/observation.hpp"
#include "gtrack/renderer.hpp"
#include "gtrack/sequence_io.hpp"
#include "gtrack/synth.hpp"
#include "support/plugins.hpp"

namespace fs = std::filesystem;

namespace {

gtrack::Setup microscope() {
  return gtrack::load_setup(fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" / "microscope_hydrogel.toml", {});
}

TEST(Synth, SegmentedFrameMatchesTheRenderedTruth) {
  const gtrack::Setup setup = microscope();
  gtrack::SynthOptions o;
  o.frames = 40;
  o.seed = 3;
  const auto plan = gtrack::plan_sequence(setup, o);
  const gtrack::ObservationConfig oc;  // the shipped defaults
  auto renderer = gtrack::make_cpu_renderer({"cpu", 0.25, 1, ""});
  renderer->set_model(setup.model());
  renderer->set_projection(setup.sensor->projection(), 0.25);
  const auto rs = renderer->render_size();
  gtrack::Segmenter seg(oc, setup.sensor->image_size(), rs);
  int checked = 0;
  for (int i = 0; i < o.frames && checked < 4; ++i) {
    gtrack::SynthVisibility vis;
    const cv::Mat frame = gtrack::render_frame(setup, plan, i, &vis);
    if (vis.occluded > 0.001 || vis.in_view < 0.999) continue;
    ++checked;
    const cv::Mat observed = seg.observe(frame).mask;
    const cv::Mat truth = renderer->render_mask(plan.frames[i].truth);
    const double inter = cv::countNonZero(observed & truth), uni = cv::countNonZero(observed | truth);
    const double ratio = static_cast<double>(cv::countNonZero(observed)) / cv::countNonZero(truth);
    EXPECT_GT(inter / uni, 0.93) << "frame " << i;
    // The outline must not be biased: a bias in size is a bias in depth.
    EXPECT_NEAR(ratio, 1.0, 0.03) << "frame " << i;
  }
  EXPECT_GE(checked, 2);
}

// A camera with lens distortion draws its frames through the lens: the
// frame the tracker undistorts (Sensor::rectify) is the one a camera
// without distortion draws, and the frame itself is not.
TEST(Synth, FramesAreDrawnThroughTheLensTheTrackerUndistorts) {
  const std::string text = "[sensor]\nplugin = \"pinhole_microscope\"\nwidth = 256\nheight = 256\nfx = 3200.0\n"
                           "distortion = [-50, 0, 0, 0]\n[gripper]\nplugin = \"hydrogel_six_finger\"\n[stimulus]\n"
                           "plugin = \"temperature_hysteresis\"\n";
  std::string plain = text;
  plain.replace(plain.find("distortion = [-50, 0, 0, 0]\n"), 28, "");
  const gtrack::Setup lens = gtrack::load_setup(gtrack::ConfigTable::parse(text, "lens.toml"), {});
  const gtrack::Setup none = gtrack::load_setup(gtrack::ConfigTable::parse(plain, "none.toml"), {});
  gtrack::SynthOptions o;
  o.frames = 4;
  o.seed = 3;
  const auto a = gtrack::plan_sequence(lens, o), b = gtrack::plan_sequence(none, o);
  EXPECT_FALSE(a.lens_map.empty());
  EXPECT_TRUE(b.lens_map.empty());
  const gtrack::ObservationConfig oc;
  gtrack::Segmenter seg(oc, {256, 256}, {256, 256});
  const auto iou = [](const cv::Mat& x, const cv::Mat& y) {
    return static_cast<double>(cv::countNonZero(x & y)) / cv::countNonZero(x | y);
  };
  for (int i = 0; i < o.frames; ++i) {
    const cv::Mat drawn = gtrack::render_frame(lens, a, i, nullptr);
    const cv::Mat linear = seg.observe(gtrack::render_frame(none, b, i, nullptr)).mask;
    EXPECT_GT(iou(seg.observe(lens.sensor->rectify(drawn)).mask, linear), 0.97) << "frame " << i;
    EXPECT_LT(iou(seg.observe(drawn).mask, linear), 0.9) << "frame " << i;
  }
}

// A probe turned in the world (its slice now the world's x-z plane) gets
// the sequence an upright one gets, turned with it: every frame's palm
// centre in its slab and its palm facing along the slice's normal as much
// as the upright probe's do.
TEST(Synth, ATurnedProbeSeesTheSequenceAnUprightOneSees) {
  const gtrack::Setup upright = gtrack::testing::probe_setup();
  const gtrack::Setup turned = gtrack::testing::probe_setup("[90, 0, 0]");
  gtrack::SynthOptions o;
  o.frames = 30;
  o.preset = "ultrasound";
  const auto a = gtrack::plan_sequence(upright, o), b = gtrack::plan_sequence(turned, o);
  const Eigen::Matrix3d frame = gtrack::rotation_from_euler_deg(90, 0, 0);
  const Eigen::Vector3d na = upright.sensor->nominal_position_mm(), nb = turned.sensor->nominal_position_mm();
  for (int i = 0; i < o.frames; ++i) {
    const Eigen::VectorXd &ha = a.frames[i].truth, &hb = b.frames[i].truth;
    EXPECT_LT((frame * (ha.head<3>() - na) - (hb.head<3>() - nb)).norm(), 1e-9) << "frame " << i;
    const Eigen::Matrix3d ra = gtrack::rotation_from_euler_deg(ha[3], ha[4], ha[5]);
    const Eigen::Matrix3d rb = gtrack::rotation_from_euler_deg(hb[3], hb[4], hb[5]);
    EXPECT_LT((frame * ra - rb).norm(), 1e-9) << "frame " << i;
    EXPECT_EQ(ha.tail(6), hb.tail(6)) << "frame " << i;
  }
}

// A slice images only its slab: the truth's in_view is the share of the
// whole gripper imaged, so a gripper tilted out of the plane is partly out
// of view and one beside the slab out of view (both had been 1: the share
// was taken of the part inside the slab).
TEST(Synth, APartOutsideASlicesSlabIsOutOfView) {
  const gtrack::Setup setup = gtrack::testing::probe_setup();
  gtrack::SynthOptions o;
  o.frames = 1;
  o.preset = "ultrasound";
  o.occlusion_scale = 0;
  auto plan = gtrack::plan_sequence(setup, o);
  Eigen::VectorXd& h = plan.frames[0].truth;
  h.head<3>() = setup.sensor->nominal_position_mm();
  h.segment<3>(3).setZero();
  gtrack::SynthVisibility flat, tilted, beside;
  gtrack::render_frame(setup, plan, 0, &flat);
  h[3] = 60;
  gtrack::render_frame(setup, plan, 0, &tilted);
  h[3] = 0;
  h.head<3>() += 5 * gtrack::viewing_axis(setup.sensor->projection());
  gtrack::render_frame(setup, plan, 0, &beside);
  EXPECT_GT(flat.in_view, 0.99);
  EXPECT_LT(tilted.in_view, 0.5);
  EXPECT_GT(tilted.in_view, 0.02);
  EXPECT_EQ(beside.in_view, 0);
  EXPECT_DOUBLE_EQ(tilted.visible, tilted.in_view);
}

// A config's camera rate ([tracker] fps) is the sequence's frame rate.
TEST(Synth, TheConfigsFrameRateIsTheSequences) {
  const std::string text = "[sensor]\nplugin = \"pinhole_microscope\"\nwidth = 256\nheight = 256\nfx = 3200.0\n"
                           "[gripper]\nplugin = \"hydrogel_six_finger\"\n[stimulus]\nplugin = "
                           "\"temperature_hysteresis\"\n[tracker]\nfps = 100.0\n";
  const gtrack::Setup setup = gtrack::load_setup(gtrack::ConfigTable::parse(text, "fps.toml"), {});
  gtrack::SynthOptions o;
  o.frames = 3;
  const auto plan = gtrack::plan_sequence(setup, o);
  EXPECT_DOUBLE_EQ(plan.preset.frame_rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(plan.frames[2].time_s, 0.02);
  std::string slow = text;
  slow.replace(slow.find("fps = 100.0"), 11, "fps = 1e-6");
  EXPECT_THROW(gtrack::plan_sequence(gtrack::load_setup(gtrack::ConfigTable::parse(slow, "fps.toml"), {}), o),
               gtrack::ConfigError);
}

TEST(Synth, SameSeedSameSequence) {
  const gtrack::Setup setup = microscope();
  gtrack::SynthOptions o;
  o.frames = 12;
  o.seed = 7;
  const auto a = gtrack::plan_sequence(setup, o), b = gtrack::plan_sequence(setup, o);
  o.seed = 8;
  const auto c = gtrack::plan_sequence(setup, o);
  for (int i = 0; i < 12; ++i) {
    EXPECT_EQ(a.frames[i].truth, b.frames[i].truth);
    EXPECT_EQ(a.frames[i].stimulus, b.frames[i].stimulus);
  }
  EXPECT_NE(a.frames[5].truth, c.frames[5].truth);
  const cv::Mat fa = gtrack::render_frame(setup, a, 9, nullptr), fb = gtrack::render_frame(setup, b, 9, nullptr);
  EXPECT_EQ(cv::norm(fa, fb, cv::NORM_INF), 0);
}

// A lab's own stimulus log drives the material in place of the profile:
// each frame takes the log's reading (interpolated, the nearest past its
// end), the joints follow it, and the seed's motion stays as it was.
TEST(Synth, ALabsStimulusLogDrivesTheMaterial) {
  const gtrack::Setup setup = microscope();
  gtrack::SynthOptions o;
  o.frames = 90;
  o.seed = 4;
  const auto profile = gtrack::plan_sequence(setup, o);
  const fs::path log = fs::temp_directory_path() / "gtrack_synth_lab_log.csv";
  // Held cold for a second, heated past the 24-27 C band, then the log ends.
  std::ofstream(log) << "time_s,T_C,humidity\n0,22,40\n1,22,40\n2,32,41\n";
  o.stimulus_log = log;
  o.stimulus_column = "T_C";
  const auto lab = gtrack::plan_sequence(setup, o);
  for (int i = 0; i < o.frames; ++i) {
    const double t = i / 30.0;
    EXPECT_DOUBLE_EQ(lab.frames[i].stimulus, t <= 1 ? 22.0 : t <= 2 ? 22 + 10 * (t - 1) : 32.0) << "frame " << i;
    EXPECT_EQ(lab.frames[i].truth.head<6>(), profile.frames[i].truth.head<6>()) << "frame " << i;
  }
  EXPECT_LT(lab.frames[25].truth[gtrack::kPoseDims], 1.0);   // still cold: unfolded
  EXPECT_GT(lab.frames[89].truth[gtrack::kPoseDims], 20.0);  // heated: folding
  // The same log on a logger's clock that started 100 s before the camera:
  // none of its rows falls within the frames, which would all take its
  // first reading, so it is refused; with its time at the first frame
  // (--stimulus-offset) it drives the material as before.
  std::ofstream(log) << "time_s,T_C,humidity\n100,22,40\n101,22,40\n102,32,41\n";
  try {
    gtrack::plan_sequence(setup, o);
    ADD_FAILURE() << "a log after the frames was taken";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(log.string() + ": its rows cover t = 100.000 to 102.000 s, and none of the "
                                         "90 frames to draw (t = 0.000 to 2.967 s) falls within them; expected "
                                         "seconds from the sequence's first frame"),
              std::string::npos)
        << e.what();
  }
  o.stimulus_offset_s = 100;
  const auto shifted = gtrack::plan_sequence(setup, o);
  fs::remove(log);
  for (int i = 0; i < o.frames; ++i) EXPECT_DOUBLE_EQ(shifted.frames[i].stimulus, lab.frames[i].stimulus) << i;
}

// A log kept as the stimulus.csv of the folder the sequence is written to
// would be replaced by the sequence's own: refused, the log and the folder
// left as they were.
TEST(Synth, ALogInTheOutputFolderIsNotOverwritten) {
  const gtrack::Setup setup = microscope();
  const fs::path out = fs::temp_directory_path() / "gtrack_synth_log_in_out";
  fs::remove_all(out);
  fs::create_directories(out / "frames");
  const std::string text = "time_s,B_mT,T_C\n0,1,22\n0.05,2,30\n0.1,3,31\n";
  std::ofstream(out / "stimulus.csv") << text;
  std::ofstream(out / "ground_truth.csv") << "an earlier sequence's truth\n";
  gtrack::SynthOptions o;
  o.frames = 3;
  o.stimulus_log = out / "." / "stimulus.csv";  // the same file by another name
  o.stimulus_column = "T_C";
  try {
    gtrack::write_synthetic_sequence(setup, o, out);
    ADD_FAILURE() << "the log was written over";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(o.stimulus_log->string() + ": is the stimulus log the sequence is made from; "
                                         "writing the sequence to " + out.string() +
                                         " would replace it with its stimulus.csv; expected another --out"),
              std::string::npos)
        << e.what();
  }
  std::ifstream in(out / "stimulus.csv");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), text);
  EXPECT_TRUE(fs::exists(out / "ground_truth.csv"));
  // Elsewhere, the same log makes the sequence.
  fs::rename(out / "stimulus.csv", out.parent_path() / "gtrack_synth_log_in_out.csv");
  o.stimulus_log = out.parent_path() / "gtrack_synth_log_in_out.csv";
  EXPECT_EQ(gtrack::write_synthetic_sequence(setup, o, out).frames, 3);
  EXPECT_TRUE(fs::exists(out / "stimulus.csv"));
  fs::remove(*o.stimulus_log);
  fs::remove_all(out);
}

TEST(Synth, OcclusionScaleShrinksTheOccludersAndKeepsTheRest) {
  const gtrack::Setup setup = microscope();
  gtrack::SynthOptions o;
  o.frames = 150;
  o.seed = 2;
  const auto full = gtrack::plan_sequence(setup, o);
  o.occlusion_scale = 0.5;
  const auto half = gtrack::plan_sequence(setup, o);
  o.occlusion_scale = 0;
  const auto none = gtrack::plan_sequence(setup, o);
  int occluded = 0;
  for (int i = 0; i < o.frames; ++i) {
    EXPECT_EQ(full.frames[i].truth, none.frames[i].truth) << "frame " << i;
    EXPECT_EQ(full.frames[i].stimulus, none.frames[i].stimulus) << "frame " << i;
    EXPECT_FALSE(none.frames[i].occluder.active) << "frame " << i;
    EXPECT_DOUBLE_EQ(half.frames[i].occluder.target, 0.5 * full.frames[i].occluder.target) << "frame " << i;
    EXPECT_EQ(half.frames[i].occluder.offset_px, full.frames[i].occluder.offset_px) << "frame " << i;
    if (full.frames[i].occluder.active) ++occluded;
  }
  EXPECT_GT(occluded, 30);
  // The same frame drawn without its occluder differs only where it was.
  int shown = -1;
  for (int i = 0; i < o.frames && shown < 0; ++i) {
    if (full.frames[i].occluder.target > 0.3) shown = i;
  }
  ASSERT_GE(shown, 0);
  gtrack::SynthVisibility vf, vn;
  const cv::Mat a = gtrack::render_frame(setup, full, shown, &vf), b = gtrack::render_frame(setup, none, shown, &vn);
  EXPECT_GT(vf.occluded, 0.2);
  EXPECT_EQ(vn.occluded, 0);
  EXPECT_EQ(vn.in_view, vf.in_view);
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  cv::cvtColor(diff, diff, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::countNonZero(diff), 0);
  EXPECT_LT(cv::countNonZero(diff), diff.total() / 4);
  o.occlusion_scale = 1.5;
  EXPECT_THROW(gtrack::plan_sequence(setup, o), gtrack::Error);
}

TEST(Synth, PlanHasOcclusionsExitsTiltsAndFolding) {
  const gtrack::Setup setup = microscope();
  gtrack::SynthOptions o;
  o.frames = 300;
  const auto plan = gtrack::plan_sequence(setup, o);
  int occluded = 0, outside = 0;
  double max_tilt = 0, q_min = 1e9, q_max = -1e9, max_step_um = 0;
  const double half_view = 0.5 * 1024 * setup.sensor->mm_per_pixel(), r = setup.model().radius_mm();
  for (size_t i = 0; i < plan.frames.size(); ++i) {
    const auto& f = plan.frames[i];
    occluded += f.occluder.active ? 1 : 0;
    EXPECT_LE(f.occluder.target, 0.8 + 1e-9);
    if (std::abs(f.truth[0]) > half_view + 0.9 * r || std::abs(f.truth[1]) > half_view + 0.9 * r) ++outside;
    max_tilt = std::max({max_tilt, std::abs(f.truth[3]), std::abs(f.truth[4])});
    EXPECT_LT(std::abs(f.truth[3]), 90);  // the palm never faces away: no mirror ambiguity in the truth
    EXPECT_LT(std::abs(f.truth[4]), 90);
    for (int k = 6; k < f.truth.size(); ++k) {
      q_min = std::min(q_min, f.truth[k]);
      q_max = std::max(q_max, f.truth[k]);
    }
    if (i > 0) max_step_um = std::max(max_step_um, 1000 * (f.truth.head<3>() - plan.frames[i - 1].truth.head<3>()).norm());
  }
  EXPECT_NEAR(occluded / 300.0, 0.7, 0.12);
  EXPECT_GT(outside, 5);
  EXPECT_GT(max_tilt, 35);
  EXPECT_LT(q_min, 3);
  EXPECT_GT(q_max, 50);
  EXPECT_LT(max_step_um, 500);
}

TEST(Synth, PerHingeNoiseMovesHingesButNotTheTruth) {
  const gtrack::Setup setup = microscope();
  gtrack::SynthOptions o;
  o.frames = 5;
  const auto clean = gtrack::plan_sequence(setup, o);
  o.joint_noise_deg = 2;
  const auto noisy = gtrack::plan_sequence(setup, o);
  EXPECT_EQ(clean.frames[3].truth, noisy.frames[3].truth);
  double spread = 0;
  for (size_t k = 0; k < noisy.frames[3].hinge_deg.size(); ++k) {
    spread += std::abs(noisy.frames[3].hinge_deg[k] - clean.frames[3].hinge_deg[k]);
  }
  EXPECT_GT(spread / noisy.frames[3].hinge_deg.size(), 0.5);
}

TEST(Synth, WritesAFolderThatATrackerConfigCanLoad) {
  const gtrack::Setup setup = microscope();
  const fs::path dir = fs::temp_directory_path() / "gtrack_synth_test";
  fs::remove_all(dir);
  gtrack::SynthOptions o;
  o.frames = 3;
  const auto s = gtrack::write_synthetic_sequence(setup, o, dir);
  EXPECT_EQ(s.frames, 3);
  for (const char* f : {"frames/000000.png", "frames/000002.png", "stimulus.csv", "ground_truth.csv", "sequence.toml"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
  const auto truth = gtrack::read_pose_table(dir / "ground_truth.csv");
  ASSERT_EQ(truth.rows.size(), 3u);
  EXPECT_EQ(truth.fingers, 6);
  EXPECT_TRUE(truth.rows[0].extra.count("visible"));
  const gtrack::Setup seq = gtrack::load_setup(dir / "sequence.toml", {});
  const gtrack::EngineConfig cfg = gtrack::engine_config(seq);
  gtrack::check_root_keys(seq);
  EXPECT_FALSE(cfg.tracker.initial_pose.has_value());
  EXPECT_DOUBLE_EQ(cfg.tracker.fps, 30);
  fs::remove_all(dir);
}

// sequence.toml is tracked from the sequence's folder, wherever the input
// config was: a gripper's model_file given relative to the input config, and
// plugin folders given on the command line, are written as absolute paths.
TEST(Synth, SequenceConfigCarriesFilesAndPluginFoldersAbsolute) {
  const fs::path base = fs::temp_directory_path() / "gtrack_synth_paths";
  fs::remove_all(base);
  fs::create_directories(base / "cfg");
  fs::create_directories(base / "extra_plugins");
  // configs/microscope_custom_gripper.toml with its [gripper] moved to a model_file.
  std::ifstream in(fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" / "microscope_custom_gripper.toml");
  std::string line, config, model;
  bool in_gripper = false;
  while (std::getline(in, line)) {
    if (line.starts_with("[")) in_gripper = line.starts_with("[gripper") || line.starts_with("[[gripper");
    if (!in_gripper) {
      config += line + "\n";
    } else if (line.starts_with("[gripper]")) {
      config += "[gripper]\nplugin = \"data_defined\"\nmodel_file = \"models/star.toml\"\n";
    } else if (!line.starts_with("plugin")) {
      model += (line.starts_with("[[gripper.finger]]") ? std::string("[[finger]]") : line) + "\n";
    }
  }
  fs::create_directories(base / "cfg" / "models");
  std::ofstream(base / "cfg" / "models" / "star.toml") << model;
  std::ofstream(base / "cfg" / "config.toml") << config;

  gtrack::SetupOptions so;
  so.plugin_paths = {base / "extra_plugins"};
  const gtrack::Setup setup = gtrack::load_setup(base / "cfg" / "config.toml", so);
  gtrack::SynthOptions o;
  o.frames = 2;
  const fs::path dir = base / "seq";
  gtrack::write_synthetic_sequence(setup, o, dir);
  std::ifstream t(dir / "sequence.toml");
  const std::string text((std::istreambuf_iterator<char>(t)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("model_file = '" + (base / "cfg" / "models" / "star.toml").string() + "'"), std::string::npos)
      << text;
  EXPECT_NE(text.find((base / "extra_plugins").string()), std::string::npos) << text;
  const gtrack::Setup seq = gtrack::load_setup(dir / "sequence.toml", {});
  EXPECT_EQ(seq.model().fingers(), 4);
  fs::remove_all(base);
}

// sequence.toml writes each float as the shortest text that reads back as
// the same double (0.45, not TOML++'s 0.45000000000000001), and leaves
// strings alone, even one that holds such a number.
TEST(Synth, SequenceConfigWritesFloatsShortAndExact) {
  const fs::path base = fs::temp_directory_path() / "gtrack_synth_floats";
  fs::remove_all(base);
  const fs::path odd_folder = base / "plugins 0.10000000000000001";
  fs::create_directories(odd_folder);
  gtrack::SetupOptions so;
  so.plugin_paths = {odd_folder};
  const fs::path config = fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" / "microscope_custom_gripper.toml";
  const gtrack::Setup setup = gtrack::load_setup(config, so);
  gtrack::SynthOptions o;
  o.frames = 2;
  gtrack::write_synthetic_sequence(setup, o, base / "seq");
  std::ifstream t(base / "seq" / "sequence.toml");
  const std::string text((std::istreambuf_iterator<char>(t)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("0000000000"), text.find("plugins 0.10000000000000001") + 11) << text;
  EXPECT_EQ(text.find("0000000000", text.find("0000000000") + 10), std::string::npos) << text;
  EXPECT_NE(text.find("[ 0.45, 0.0 ]"), std::string::npos) << text;
  const auto original = gtrack::ConfigTable::parse(
      [&] {
        std::ifstream in(config);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      }(),
      config.string());
  const auto written = gtrack::ConfigTable::parse(text, "sequence.toml");
  EXPECT_EQ(written.table("gripper").number_rows("palm_mm", 2), original.table("gripper").number_rows("palm_mm", 2));
  EXPECT_EQ(written.table("gripper").tables("finger").at(0).numbers("link_lengths_mm"),
            original.table("gripper").tables("finger").at(0).numbers("link_lengths_mm"));
  fs::remove_all(base);
}

// The config's [synth] table sets the stimulus profile in the plugin's own
// units; misspelt keys and an empty range are one-line errors that name the
// file, the line and the key, raised before the output folder is touched.
gtrack::Setup microscope_with(const std::string& synth_table) {
  const fs::path file = fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" / "microscope_hydrogel.toml";
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return gtrack::load_setup(gtrack::ConfigTable::parse(text + "\n[synth]\n" + synth_table, "with_synth.toml"), {});
}

TEST(Synth, SynthTableSetsTheStimulusProfile) {
  gtrack::SynthOptions o;
  o.frames = 300;
  const auto preset = gtrack::plan_sequence(microscope(), o);
  const auto own = gtrack::plan_sequence(microscope_with("stimulus_low = 40\nstimulus_high = 90\nstimulus_noise = 0\n"), o);
  EXPECT_DOUBLE_EQ(own.preset.stimulus_low, 40);
  EXPECT_DOUBLE_EQ(own.preset.stimulus_high, 90);
  double lo = 1e9, hi = -1e9, preset_hi = -1e9;
  for (const auto& f : own.frames) lo = std::min(lo, f.stimulus), hi = std::max(hi, f.stimulus);
  for (const auto& f : preset.frames) preset_hi = std::max(preset_hi, f.stimulus);
  EXPECT_DOUBLE_EQ(lo, 40);  // the profile holds at both ends, and there is no reading noise
  EXPECT_DOUBLE_EQ(hi, 90);
  EXPECT_LT(preset_hi, 31);
  // Only the stimulus changed: the motion of a seed is the same.
  EXPECT_EQ(own.frames[100].truth.head<6>(), preset.frames[100].truth.head<6>());
}

// The depth range, the one set in millimetres, for a gripper of another
// size than the preset's: the path along the line of sight is scaled, the
// rest of the motion kept.
TEST(Synth, SynthTableSetsTheDepthRange) {
  gtrack::SynthOptions o;
  o.frames = 300;
  const auto preset = gtrack::plan_sequence(microscope(), o);
  const auto own = gtrack::plan_sequence(microscope_with("depth_amplitude_mm = 0.1\n"), o);
  EXPECT_DOUBLE_EQ(own.preset.depth_amplitude_mm, 0.1);
  double nominal = 0;
  for (const auto& f : preset.frames) nominal += f.truth[2] / preset.frames.size();
  double preset_reach = 0, own_reach = 0;
  for (size_t i = 0; i < own.frames.size(); ++i) {
    preset_reach = std::max(preset_reach, std::abs(preset.frames[i].truth[2] - nominal));
    own_reach = std::max(own_reach, std::abs(own.frames[i].truth[2] - nominal));
    EXPECT_EQ(own.frames[i].truth.head<2>(), preset.frames[i].truth.head<2>());
  }
  EXPECT_GT(preset_reach, 0.2);
  EXPECT_LT(own_reach, 0.12);
  EXPECT_NEAR(own_reach / preset_reach, 0.25, 0.05);
}

TEST(Synth, SynthTableErrorsNameTheKeyAndLeaveTheFolderAlone) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_synth_table_error";
  fs::remove_all(dir);
  gtrack::SynthOptions o;
  o.frames = 2;
  auto message = [&](const std::string& table) {
    try {
      gtrack::write_synthetic_sequence(microscope_with(table), o, dir);
    } catch (const gtrack::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string typo = message("stimulus_low = 0\nstimulus_hgh = 80\n");
  EXPECT_NE(typo.find("with_synth.toml:"), std::string::npos) << typo;
  EXPECT_NE(typo.find("synth.stimulus_hgh"), std::string::npos) << typo;
  EXPECT_NE(typo.find("did you mean 'stimulus_high'"), std::string::npos) << typo;
  const std::string empty = message("stimulus_low = 50\nstimulus_high = 40\n");
  EXPECT_NE(empty.find("synth.stimulus_high"), std::string::npos) << empty;
  EXPECT_NE(empty.find("greater than stimulus_low"), std::string::npos) << empty;
  EXPECT_NE(message("stimulus_period_s = 0\n").find("synth.stimulus_period_s"), std::string::npos);
  EXPECT_NE(message("depth_amplitude_mm = -1\n").find("synth.depth_amplitude_mm"), std::string::npos);
  // Readings the stimulus plugin refuses (a profile in kelvin), by their key,
  // however few frames would reach them.
  const std::string kelvin = message("stimulus_low = 295.0\nstimulus_high = 305.0\n");
  EXPECT_NE(kelvin.find("key 'synth.stimulus_low': the stimulus plugin refused the reading 295, the profile's low "
                        "end, as a first reading at t = 0: a reading of 295"),
            std::string::npos)
      << kelvin;
  const std::string noise = message("stimulus_noise = 1e9\n");
  EXPECT_NE(noise.find("key 'synth.stimulus_noise': a reading of"), std::string::npos) << noise;
  EXPECT_FALSE(fs::exists(dir));
}

}  // namespace
