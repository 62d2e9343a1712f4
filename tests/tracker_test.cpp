// The tracker end to end on small synthetic scenes: coarse search, frame to
// frame tracking, files written by track_sequence, interruption, bad inputs.
#include <gtest/gtest.h>
#include <fcntl.h>

#include <opencv2/imgproc.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>
#include <thread>
#include <utility>

#include "gtrack/engine_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/evaluation.hpp"
#include "gtrack/model.hpp"
#include "gtrack/results.hpp"
#include "gtrack/synth.hpp"
#include "gtrack/tracker.hpp"
#include "gtrack/tracker_state.hpp"
#include "support/plugins.hpp"

namespace fs = std::filesystem;

namespace {

const char* const kConfig = gtrack::testing::kSmallMicroscopeConfig;

gtrack::Setup make_setup(const std::string& extra = "") { return gtrack::testing::small_microscope_setup(extra); }

// The message of the ConfigError that engine_config raises for the test
// config plus `extra` (a test failure, and "", when it raises none).
std::string engine_config_error(const std::string& extra) {
  auto setup = make_setup(extra);
  try {
    gtrack::engine_config(setup);
  } catch (const gtrack::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << extra << ": expected ConfigError";
  return "";
}

// The gripper at h as the cpu backend renders it, at the image's size.
cv::Mat rendered_mask(const gtrack::Setup& setup, const Eigen::VectorXd& h) {
  gtrack::RenderOptions ro;
  ro.backend = "cpu";
  ro.scale = 1.0;
  auto r = gtrack::make_cpu_renderer(ro);
  r->set_model(setup.model());
  r->set_projection(setup.sensor->projection(), 1.0);
  return r->render_mask(h);
}

// A camera frame of the gripper at h: red-ish gripper on a grey, noisy background.
cv::Mat scene(const gtrack::Setup& setup, const Eigen::VectorXd& h, std::uint64_t seed) {
  const cv::Mat mask = rendered_mask(setup, h);
  cv::Mat img(mask.size(), CV_8UC3, cv::Scalar(120, 125, 130));
  cv::Mat noise(mask.size(), CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, 6);
  img.setTo(cv::Scalar(60, 70, 200), mask);
  cv::add(img, noise, img);
  return img;
}

Eigen::VectorXd pose(double x, double y, double rz, double q) {
  Eigen::VectorXd h(12);
  h << x, y, 100.0, 8, -6, rz, q, q, q, q, q, q;
  return h;
}

fs::path temp_dir(const std::string& name) {
  const fs::path p = fs::path(GTRACK_TEST_BINARY_DIR) / "test_tmp" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

std::vector<std::string> lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

int fields(const std::string& line) { return static_cast<int>(std::count(line.begin(), line.end(), ',')) + 1; }

// A sequence on disk: frames/NNNNNN.png and stimulus.csv (heating 22 -> 30 C).
fs::path write_sequence(const std::string& name, int frames) {
  const fs::path dir = temp_dir(name);
  fs::create_directories(dir / "frames");
  const auto setup = make_setup();
  std::ofstream csv(dir / "stimulus.csv");
  csv << "frame,value\n";
  for (int i = 0; i < frames; ++i) {
    char n[32];
    std::snprintf(n, sizeof n, "%06d.png", i);
    cv::imwrite((dir / "frames" / n).string(), scene(setup, pose(0.3 + 0.03 * i, -0.2, 20 + i, 5 + i), i + 1));
    csv << i << "," << 22.0 + 8.0 * i / std::max(1, frames - 1) << "\n";
  }
  return dir;
}

TEST(Tracker, CoarseSearchFindsTheGripperOnTheFirstFrame) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  gtrack::Tracker tracker(setup, config);
  const Eigen::VectorXd truth = pose(0.4, -0.3, 25, 15);
  const auto e = tracker.process(scene(setup, truth, 1), 0, 0.0, 22.0);
  EXPECT_EQ(e.status, gtrack::TrackStatus::Search);
  EXPECT_LT(e.terms.dice, 0.12) << e.hypothesis.transpose();
  EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.06) << e.hypothesis.transpose();
  EXPECT_GT(e.evaluations, 800u);
}

// A blob of the gripper's colour apart from it (a reflector, a caliper mark)
// pulls the centroid of O off the gripper: the coarse search also starts
// from the largest blob, and finds the gripper.
TEST(Tracker, CoarseSearchFindsTheGripperBesideABlobOfItsColour) {
  // The gripper ~32 px across in a 256 px image, the search box all of it.
  std::string config = kConfig;
  config.replace(config.find("fx = 3200.0"), 11, "fx = 800.0");
  config.replace(config.find("[-3.0, -3.0, 98.0]"), 18, "[-15.0, -15.0, 98.0]");
  config.replace(config.find("[3.0, 3.0, 102.0]"), 17, "[15.0, 15.0, 102.0]");
  auto setup = gtrack::load_setup(gtrack::ConfigTable::parse(config, "<test>"), {});
  const auto engine = gtrack::engine_config(setup);
  gtrack::Tracker tracker(setup, engine);
  const Eigen::VectorXd truth = pose(-6, -6, 25, 15);
  cv::Mat image = scene(setup, truth, 1);
  cv::circle(image, {224, 224}, 8, cv::Scalar(60, 70, 200), cv::FILLED);  // 12 mm, 12 mm
  const auto e = tracker.process(image, 0, 0.0, 22.0);
  EXPECT_EQ(e.status, gtrack::TrackStatus::Search);
  EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.3) << e.hypothesis.transpose();
}

// A gripper moving three times the swarm's x spread per frame: frame 1 is
// found again by re-detection, and the step between the two found estimates
// starts particle 1 of frame 2, which then follows without re-detection.
// The step is part of the tracker's state (it survives a resume).
TEST(Tracker, TheStepBetweenTwoFoundFramesStartsTheNextSwarm) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  gtrack::Tracker tracker(setup, config);
  const double step = 0.6;
  const auto truth = [&](int i) { return pose(-1.2 + step * i, 0.1, 30, 0); };
  const auto e0 = tracker.process(scene(setup, truth(0), 1), 0, 0.0, 22.0);
  ASSERT_EQ(e0.status, gtrack::TrackStatus::Search);
  EXPECT_TRUE(tracker.state().last_found);
  EXPECT_FALSE(tracker.state().found_step);
  const auto e1 = tracker.process(scene(setup, truth(1), 2), 1, 1 / 30.0, 22.0);
  ASSERT_TRUE(e1.redetected) << e1.hypothesis.transpose();
  const auto s1 = tracker.state();
  ASSERT_TRUE(s1.found_step);
  EXPECT_NEAR((*s1.found_step)[0], step, 0.1);
  EXPECT_NEAR((*s1.found_step)[1], 0, 0.1);
  const auto e2 = tracker.process(scene(setup, truth(2), 3), 2, 2 / 30.0, 22.0);
  EXPECT_FALSE(e2.redetected);
  EXPECT_LT((e2.hypothesis.head<2>() - truth(2).head<2>()).norm(), 0.06) << e2.hypothesis.transpose();
  EXPECT_FALSE(tracker.state().last_found);
  EXPECT_FALSE(tracker.state().found_step);

  // Through the state file.
  const fs::path file = temp_dir("found_step") / "tracker_state.txt";
  gtrack::write_tracker_state(file, s1);
  const gtrack::TrackerState back = gtrack::read_tracker_state(file);
  EXPECT_TRUE(back.last_found);
  ASSERT_TRUE(back.found_step);
  EXPECT_EQ(*back.found_step, *s1.found_step);
  gtrack::Tracker resumed(setup, config);
  resumed.restore(back);
  EXPECT_EQ(*resumed.state().found_step, *s1.found_step);
  std::ofstream(file) << "gtrack-tracker-state 1\nframe 1\nfound_step 1 2 3\n";
  try {
    gtrack::read_tracker_state(file);
    ADD_FAILURE() << "a found step of three values was read";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tracker_state.txt:3: expected '-' or two values (x, y) after 'found_step'"),
              std::string::npos)
        << e.what();
  }
}

TEST(Tracker, FollowsAMovingFoldingGripper) {
  auto setup = make_setup();
  auto config = gtrack::engine_config(setup);
  config.tracker.redetect_dice = 1.0;  // the swarm's own budget (re-detection has its tests)
  gtrack::Tracker tracker(setup, config);
  tracker.set_estimate(pose(0.3, -0.2, 20, 5));
  for (int i = 0; i < 8; ++i) {
    const Eigen::VectorXd truth = pose(0.3 + 0.03 * i, -0.2, 20 + i, 5 + 2 * i);
    const auto e = tracker.process(scene(setup, truth, i + 1), i, i / 30.0, 22.0 + i);
    EXPECT_EQ(e.status, gtrack::TrackStatus::Tracked);
    // N x G per tracked frame, the mirror check's N/2 x G/2 (the gripper
    // is tilted by 10 deg), the refinement's N x G and the unseen-finger
    // check's 6 (one a finger), plus one when it fills some in.
    EXPECT_FALSE(e.redetected);
    EXPECT_GE(e.evaluations, 32u * 25u + 16u * 12u + 32u * 25u + 6u);
    EXPECT_LE(e.evaluations, 32u * 25u + 16u * 12u + 32u * 25u + 7u);
    EXPECT_LT(e.terms.dice, 0.12) << "frame " << i;
    EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.05) << "frame " << i;
  }
}

// A half-covered gripper image: the part left of the model's projected
// centre hidden behind background grey.
cv::Mat half_covered(gtrack::Tracker& tracker, const gtrack::Setup& setup, const Eigen::VectorXd& truth,
                     std::uint64_t seed) {
  cv::Mat img = scene(setup, truth, seed);
  const cv::Mat mask = tracker.renderer().render_mask(truth);
  const cv::Moments m = cv::moments(mask, true);
  EXPECT_GT(m.m00, 0) << "the model is not in view";
  const int cx = m.m00 > 0 ? static_cast<int>(m.m10 / m.m00 * img.cols / mask.cols) : img.cols / 2;
  img(cv::Rect(0, 0, cx, img.rows)).setTo(cv::Scalar(120, 125, 130));
  return img;
}

// [cost] occlusion_discount: when half of the gripper disappears behind a
// grey occluder, rendered pixels outside O are down-weighted (w < 1) and the
// track holds where the paper's D would shrink the model onto what is left.
TEST(Tracker, TheSwarmStartsFromJointsTheStimulusAllows) {
  // The previous estimate is open (5 deg) but the reading says folded
  // (30 C, above the band from the first frame: 60 +- 10 deg). The swarm
  // starts within the allowed range instead of walking there on the penalty.
  auto setup = make_setup();
  auto config = gtrack::engine_config(setup);
  config.tracker.redetect_dice = 1.0;
  config.tracker.mirror_check = false;
  gtrack::Tracker tracker(setup, config);
  tracker.set_estimate(pose(0.3, -0.2, 20, 5));
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 60);
  const auto e = tracker.process(scene(setup, truth, 3), 0, 0.0, 30.0);
  ASSERT_EQ(e.status, gtrack::TrackStatus::Tracked);
  EXPECT_DOUBLE_EQ(e.terms.stimulus, 0.0) << e.hypothesis.transpose();
  for (int f = 0; f < 6; ++f) EXPECT_NEAR(e.hypothesis[gtrack::kPoseDims + f], 60.0, 10.0) << e.hypothesis.transpose();
}

TEST(Tracker, OcclusionDiscountsRenderedPixelsOutsideO) {
  auto setup = make_setup();
  auto config = gtrack::engine_config(setup);
  config.cost.occlusion_discount = 1.0;
  config.cost.occlusion_budget = 0;  // the discount on its own
  config.cost.temporal = 0.05;
  // The swarm alone: the refinement lowers this opt-in cost further, and on
  // frame 3 its minimum lies 0.105 mm off (CMA-ES) under the half cover.
  config.tracker.refine_spread = 0;
  gtrack::Tracker tracker(setup, config);
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 5);
  tracker.set_estimate(truth);
  const auto clean = tracker.process(scene(setup, truth, 1), 0, 0.0, 22.0);
  EXPECT_DOUBLE_EQ(clean.outside_weight, 1.0);
  for (int i = 1; i < 4; ++i) {
    const auto e = tracker.process(half_covered(tracker, setup, truth, i + 1), i, i / 30.0, 22.0);
    EXPECT_EQ(e.status, gtrack::TrackStatus::Tracked);
    EXPECT_LT(e.outside_weight, 0.8) << "frame " << i;
    EXPECT_GT(e.outside_weight, 0.2) << "frame " << i;
    EXPECT_GT(e.terms.temporal, 0.0) << "frame " << i;
    EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.1) << "frame " << i;
  }
  // The paper's cost: no discount.
  config.cost.occlusion_discount = 0;
  gtrack::Tracker paper(setup, config);
  paper.set_estimate(truth);
  cv::Mat img = scene(setup, truth, 9);
  img(cv::Rect(0, 0, img.cols / 2, img.rows)).setTo(cv::Scalar(120, 125, 130));
  EXPECT_DOUBLE_EQ(paper.process(img, 0, 0.0, 22.0).outside_weight, 1.0);
}

TEST(Tracker, TheTemporalTermMeasuresThePoseAgainstItsConstantVelocity) {
  // T is the mean of ((h_d - p_d) / sigma_d)^2 over the six pose parameters,
  // p = last + (last - before last) with depth held, sigma = init_spread; and
  // over the joints, p = the middle of the range the stimulus allows now,
  // sigma = temporal_joint_sigma_deg (left out at 0). Recomputed here from
  // the estimates themselves, with the joints in T and without.
  for (const double joint_sigma : {3.0, 0.0}) {
    auto setup = make_setup();
    auto config = gtrack::engine_config(setup);
    config.tracker.redetect_dice = 1.0;
    config.tracker.mirror_check = false;
    config.cost.temporal_joint_sigma_deg = joint_sigma;
    ASSERT_GT(config.cost.temporal, 0.0);
    gtrack::Tracker tracker(setup, config);
    tracker.set_estimate(pose(0.3, -0.2, 20, 5));
    std::vector<Eigen::VectorXd> h;
    for (int i = 0; i < 4; ++i) {
      // Moving and folding faster and faster: a joint velocity would not fit.
      const auto e = tracker.process(scene(setup, pose(0.3 + 0.04 * i, -0.2, 20 + 2 * i, 5 + 3 * i * i), i + 1), i,
                                     i / 30.0, 22.0);
      ASSERT_EQ(e.status, gtrack::TrackStatus::Tracked);
      h.push_back(e.hypothesis);
      if (i < 2) continue;
      Eigen::VectorXd p = h[i - 1] + (h[i - 1] - h[i - 2]);
      p[2] = h[i - 1][2];
      double t = 0;
      for (int d = 0; d < gtrack::kPoseDims; ++d) {
        double diff = h[i][d] - p[d];
        if (d == 5) diff = std::remainder(diff, 360.0);
        t += std::pow(diff / config.tracker.init_spread[d], 2);
      }
      int used = gtrack::kPoseDims;
      if (joint_sigma > 0) {
        const auto st = setup.stimulus->state();
        ASSERT_LT(st.feasible_max_deg - st.feasible_min_deg, 100.0);  // a bounded range
        const double middle = 0.5 * (st.feasible_min_deg + st.feasible_max_deg);
        for (Eigen::Index d = gtrack::kPoseDims; d < h[i].size(); ++d, ++used) {
          t += std::pow((h[i][d] - middle) / joint_sigma, 2);
        }
      }
      EXPECT_NEAR(e.terms.temporal, t / used, 1e-9) << "frame " << i << ", joint sigma " << joint_sigma;
    }
  }
}

TEST(Tracker, NothingDetectedIsLostNotAnError) {
  auto setup = make_setup();
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  tracker.set_estimate(pose(0.3, -0.2, 20, 5));
  const cv::Mat empty(256, 256, CV_8UC3, cv::Scalar(120, 125, 130));
  const auto e = tracker.process(empty, 0, 0.0, std::nullopt);
  EXPECT_EQ(e.status, gtrack::TrackStatus::Lost);
  EXPECT_EQ(e.observed_pixels, 0u);
  EXPECT_EQ(e.hypothesis, pose(0.3, -0.2, 20, 5));  // held
}

// A frame whose search ends above [tracker] lost_dice reports the estimate
// the track holds, not the result it did not take.
TEST(Tracker, AFrameLostByItsCostReportsTheHeldEstimate) {
  auto setup = make_setup("[tracker]\nlost_dice = 0.0001\n");
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  const Eigen::VectorXd held = pose(0.3, -0.2, 20, 5);
  tracker.set_estimate(held);
  const auto e = tracker.process(scene(setup, pose(0.35, -0.15, 24, 9), 2), 0, 0.0, std::nullopt);
  ASSERT_EQ(e.status, gtrack::TrackStatus::Lost);
  EXPECT_GT(e.observed_pixels, 0u);
  EXPECT_EQ(e.hypothesis, held);
  EXPECT_EQ(*tracker.last_estimate(), held);
  EXPECT_DOUBLE_EQ(e.terms.total, tracker.score(held).total);
}

// A first search that is refused (its best D above lost_dice: a speck, not
// the gripper) gives the frame's guess but no track: the next frame searches
// the whole image again instead of looking around the refused guess.
TEST(Tracker, ARefusedFirstSearchAnchorsNoTrack) {
  auto setup = make_setup("[tracker]\nlost_dice = 0.3\n");
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  cv::Mat speck(256, 256, CV_8UC3, cv::Scalar(120, 125, 130));
  cv::rectangle(speck, cv::Rect(12, 12, 5, 5), cv::Scalar(60, 70, 200), cv::FILLED);
  const auto first = tracker.process(speck, 0, 0.0, std::nullopt);
  ASSERT_EQ(first.status, gtrack::TrackStatus::Lost);
  EXPECT_GT(first.observed_pixels, 0u);
  EXPECT_GT(first.terms.dice, 0.3);
  EXPECT_FALSE(tracker.last_estimate().has_value());
  const Eigen::VectorXd truth = pose(0.6, 0.5, 20, 5);
  const auto e = tracker.process(scene(setup, truth, 2), 1, 1 / 30.0, std::nullopt);
  EXPECT_EQ(e.status, gtrack::TrackStatus::Search);
  EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.1);
}

// process() refuses what it cannot track with an InputError and, for a
// frame of the wrong size, leaves the tracker as it was: a state saved
// after the refusal does not claim the frame.
TEST(Tracker, ARefusedFrameTimeOrReadingLeavesTheTrackerAsItWas) {
  auto setup = make_setup();
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  const cv::Mat frame = scene(setup, pose(0.3, -0.2, 20, 5), 1);
  tracker.process(frame, 0, 0.0, 24.0);
  const auto before = tracker.state();
  EXPECT_THROW(tracker.process(cv::Mat(100, 100, CV_8UC3, cv::Scalar(0, 0, 0)), 1, 0.033, 24.0), gtrack::InputError);
  EXPECT_EQ(tracker.state().frame, before.frame);
  EXPECT_EQ(*tracker.state().last, *before.last);
  const auto message = [&](double time_s, std::optional<double> reading) {
    try {
      tracker.process(frame, 1, time_s, reading);
    } catch (const gtrack::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(std::nan(""), 24.0), "frame 1: its time is nan; expected a finite number of seconds");
  EXPECT_EQ(message(0.033, std::numeric_limits<double>::infinity()),
            "frame 1: its stimulus reading is inf; expected a finite number");
  EXPECT_EQ(tracker.state().frame, before.frame);
  // A reading the plugin refuses names the frame and the reading.
  EXPECT_EQ(message(0.033, 295.0).rfind("frame 1 (t = 0.033 s): the stimulus plugin refused the reading 295: ", 0), 0u)
      << message(0.033, 295.0);
  EXPECT_EQ(tracker.state().frame, before.frame);
  EXPECT_THROW(tracker.set_estimate(Eigen::VectorXd::Constant(12, std::nan(""))), gtrack::Error);
}

// reset(): the next frame starts like the first, the stimulus plugin's state
// included (a heated gripper's plugin had kept its fold).
TEST(Tracker, ResetStartsTheStimulusAgain) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  const cv::Mat frame = scene(setup, pose(0.3, -0.2, 20, 5), 1);
  gtrack::Tracker fresh(make_setup(), config);
  const auto first = fresh.process(frame, 0, 0.0, 22.0);
  gtrack::Tracker used(setup, config);
  for (int i = 0; i < 4; ++i) used.process(frame, i, i / 30.0, 22.0 + 5 * i);  // heated past its fold
  used.reset();
  EXPECT_EQ(used.process(frame, 0, 0.0, 22.0).hypothesis, first.hypothesis);
}

// A stimulus the application put in the Setup itself is its own: reset()
// leaves it (and its state) as it is.
TEST(Tracker, ResetKeepsAStimulusTheApplicationSet) {
  struct Counting final : gtrack::Stimulus {
    int updates = 0;
    void update(double, double) override { ++updates; }
    gtrack::StimulusState state() const override { return {}; }
    double penalty(std::span<const double>) const override { return 0; }
    double fold_fraction() const override { return 0.5; }
    double target_joint_deg(double c) const override { return c; }
  };
  auto setup = make_setup();
  auto own = std::make_shared<Counting>();
  setup.stimulus = own;
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  const cv::Mat frame = scene(setup, pose(0.3, -0.2, 20, 5), 1);
  tracker.process(frame, 0, 0.0, 24.0);
  tracker.reset();
  tracker.process(frame, 0, 0.0, 24.0);
  EXPECT_EQ(own->updates, 2);
}

// After restore() the tracker holds no observation: score() says so.
TEST(Tracker, ScoreAfterARestoreNeedsAFrame) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  gtrack::Tracker a(setup, config);
  a.process(scene(setup, pose(0.3, -0.2, 20, 5), 1), 0, 0.0, 24.0);
  auto other = make_setup();
  gtrack::Tracker b(other, config);
  b.restore(a.state());
  EXPECT_THROW(b.score(pose(0.3, -0.2, 20, 5)), gtrack::Error);
  EXPECT_NO_THROW(a.score(pose(0.3, -0.2, 20, 5)));
}

// The tracker searches in the sensor's own frame: a probe turned in the
// world (looking down world -z, its slice the world's x-z plane) that sees
// the images an upright probe sees gives the upright probe's estimates,
// turned with it, and scores them as it does. Searched in the world's
// frame, its tilts were taken about the wrong axes (60 deg off on average).
TEST(Tracker, ATurnedProbeIsTrackedAsTheUprightOne) {
  const std::string engine = "[render]\nbackend = \"cpu\"\nthreads = 2\n";
  const auto upright = gtrack::testing::probe_setup("", engine);
  const auto turned = gtrack::testing::probe_setup("[-90, 0, 0]", engine);
  const gtrack::SensorFrame frame = gtrack::sensor_frame(*turned.sensor);
  ASSERT_TRUE(gtrack::sensor_frame(*upright.sensor).is_world());
  ASSERT_LT((frame.axes * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  gtrack::SynthOptions o;
  o.frames = 8;
  o.seed = 3;
  o.preset = "ultrasound";
  const auto plan_u = gtrack::plan_sequence(upright, o), plan_t = gtrack::plan_sequence(turned, o);
  gtrack::Tracker tu(upright, gtrack::engine_config(upright)), tt(turned, gtrack::engine_config(turned));
  // The upright probe's configurations as the turned probe sees them.
  const Eigen::Vector3d shift = turned.sensor->nominal_position_mm() - upright.sensor->nominal_position_mm();
  const auto as_turned = [&](Eigen::VectorXd h) {
    h.head<3>() += shift;
    return frame.to_world(h);
  };
  for (int i = 0; i < o.frames; ++i) {
    const cv::Mat image_u = gtrack::render_frame(upright, plan_u, i, nullptr);
    const cv::Mat image_t = gtrack::render_frame(turned, plan_t, i, nullptr);
    ASSERT_EQ(cv::norm(image_u, image_t, cv::NORM_INF), 0) << "frame " << i;
    const auto eu = tu.process(image_u, i, plan_u.frames[i].time_s, plan_u.frames[i].stimulus);
    const auto et = tt.process(image_t, i, plan_t.frames[i].time_s, plan_t.frames[i].stimulus);
    const Eigen::VectorXd expected = as_turned(eu.hypothesis);
    EXPECT_LT((et.hypothesis.head<3>() - expected.head<3>()).norm(), 1e-3) << "frame " << i;
    EXPECT_LT(gtrack::geodesic_angle_deg(et.hypothesis.segment<3>(3), expected.segment<3>(3)), 0.1) << "frame " << i;
    EXPECT_LT((et.hypothesis.tail(6) - eu.hypothesis.tail(6)).cwiseAbs().maxCoeff(), 0.1) << "frame " << i;
    // The public functions take the world's configurations.
    EXPECT_NEAR(tt.score(et.hypothesis).total, et.terms.total, 1e-6) << "frame " << i;
    EXPECT_NEAR(tt.score(as_turned(plan_u.frames[i].truth)).total, tu.score(plan_u.frames[i].truth).total, 1e-6)
        << "frame " << i;
    const Eigen::VectorXd last_u = as_turned(*tu.last_estimate()), last_t = *tt.last_estimate();
    EXPECT_LT((last_t.head<3>() - last_u.head<3>()).norm(), 1e-3) << "frame " << i;
    EXPECT_LT(gtrack::geodesic_angle_deg(last_t.segment<3>(3), last_u.segment<3>(3)), 0.1) << "frame " << i;
  }
}

// `initial_pose` starts the first frame that shows the gripper, also when
// frames before it showed nothing: the track starts there (status tracked),
// not from a coarse search.
TEST(Tracker, InitialPoseOutlastsEmptyFirstFrames) {
  auto setup = make_setup("[tracker]\ninitial_pose = [0.1, 0.1, 100.0, 8, -6, 10, 10, 10, 10, 10, 10, 10]\n");
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  const cv::Mat empty(256, 256, CV_8UC3, cv::Scalar(120, 125, 130));
  for (int i = 0; i < 2; ++i) EXPECT_EQ(tracker.process(empty, i, 0.1 * i, std::nullopt).status, gtrack::TrackStatus::Lost);
  const auto e = tracker.process(scene(setup, pose(0.1, 0.1, 10, 10), 3), 2, 0.2, std::nullopt);
  EXPECT_EQ(e.status, gtrack::TrackStatus::Tracked);
  EXPECT_LT((e.hypothesis.head<2>() - pose(0.1, 0.1, 10, 10).head<2>()).norm(), 0.1);
}

TEST(Tracker, SameSeedSameEstimates) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  const cv::Mat frame = scene(setup, pose(0.1, 0.1, 10, 10), 3);
  gtrack::Tracker a(setup, config), b(setup, config);
  a.set_estimate(pose(0.12, 0.08, 12, 8));
  b.set_estimate(pose(0.12, 0.08, 12, 8));
  EXPECT_EQ(a.process(frame, 4, 0.1, 23.0).hypothesis, b.process(frame, 4, 0.1, 23.0).hypothesis);
}

// JSON is UTF-8: an image name that is not (Latin-1 bytes) is written with
// those bytes as \u00XX, and a UTF-8 one as it is; a consumer's parser had
// failed on the raw bytes.
TEST(Results, AnImageNameThatIsNotUtf8IsStillJson) {
  gtrack::Estimate e;
  e.hypothesis = Eigen::VectorXd::Zero(12);
  e.image = "caf\xc3\xa9_\xff\xfe\xed\xa0\x80.png";  // é, two Latin-1 bytes, an encoded surrogate
  const std::string j = gtrack::estimate_json(e);
  EXPECT_NE(j.find("\"image\":\"caf\xc3\xa9_\\u00ff\\u00fe\\u00ed\\u00a0\\u0080.png\""), std::string::npos) << j;
}

TEST(TrackSequence, WritesEstimatesOverlayAndSummary) {
  const fs::path seq = write_sequence("seq_files", 5);
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  gtrack::TrackOptions opt;
  opt.input = (seq / "frames").string();
  opt.stimulus_csv = seq / "stimulus.csv";
  opt.out_dir = seq / "out";
  opt.save_masks = true;
  opt.progress = false;
  const auto s = gtrack::track_sequence(setup, config, opt);
  EXPECT_EQ(s.frames, 5);
  EXPECT_EQ(s.lost_frames, 0);
  const auto csv = lines(opt.out_dir / "estimates.csv");
  ASSERT_EQ(csv.size(), 6u);
  EXPECT_EQ(csv[0], "frame,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,cost,status,time_s,ms");
  for (size_t i = 1; i < csv.size(); ++i) EXPECT_EQ(fields(csv[i]), 17) << csv[i];
  EXPECT_NE(csv[1].find(",search,"), std::string::npos);
  EXPECT_NE(csv[2].find(",ok,"), std::string::npos);
  const auto jsonl = lines(opt.out_dir / "estimates.jsonl");
  ASSERT_EQ(jsonl.size(), 5u);
  EXPECT_NE(jsonl[4].find("\"stimulus\":30,"), std::string::npos) << jsonl[4];
  EXPECT_NE(jsonl[0].find("\"D\":"), std::string::npos);
  EXPECT_NE(jsonl[0].find("\"unseen_fingers\":["), std::string::npos) << jsonl[0];
  // Each row's time is the frame's place at the folder's frame rate, the
  // same in both files.
  for (size_t i = 0; i < jsonl.size(); ++i) {
    const std::string row = csv[i + 1].substr(0, csv[i + 1].rfind(','));  // less ms
    const std::string t = row.substr(row.rfind(',') + 1);
    // (The JSON line's exactly, for a run read back; the table's to the microsecond.)
    const auto json_t = gtrack::json_field(jsonl[i], "time_s");
    ASSERT_TRUE(json_t.has_value()) << jsonl[i];
    EXPECT_EQ(std::stod(std::string(*json_t)), static_cast<double>(i) / 30.0) << jsonl[i];
    EXPECT_NEAR(std::stod(t), static_cast<double>(i) / 30.0, 1e-6) << csv[i + 1];
  }
  // Each row names its image and when it was written.
  EXPECT_NE(jsonl[4].find("\"image\":\"" + (seq / "frames" / "000004.png").string() + "\""), std::string::npos)
      << jsonl[4];
  const auto stamp = jsonl[4].find("\"unix_time_s\":");
  ASSERT_NE(stamp, std::string::npos) << jsonl[4];
  const double written = std::stod(jsonl[4].substr(stamp + 14));
  const double now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  EXPECT_GT(written, now - 600);
  EXPECT_LE(written, now);
  // Read before it was tracked and written.
  const auto read_at = jsonl[4].find("\"read_unix_s\":");
  ASSERT_NE(read_at, std::string::npos) << jsonl[4];
  const double read = std::stod(jsonl[4].substr(read_at + 14));
  EXPECT_GT(read, now - 600);
  EXPECT_LE(read, written);
  // The image file's own time: when it was written, before it was read.
  const auto file_at = jsonl[4].find("\"written_unix_s\":");
  ASSERT_NE(file_at, std::string::npos) << jsonl[4];
  const double file_time = std::stod(jsonl[4].substr(file_at + 17));
  const double expected = std::chrono::duration<double>(
                              std::chrono::file_clock::to_sys(fs::last_write_time(seq / "frames" / "000004.png"))
                                  .time_since_epoch())
                              .count();
  EXPECT_NEAR(file_time, expected, 1e-5);
  EXPECT_LE(file_time, read + 1e-3);
  EXPECT_TRUE(fs::exists(opt.out_dir / "summary.json"));
  EXPECT_TRUE(fs::exists(opt.out_dir / "masks" / "000004.png"));
  EXPECT_FALSE(s.overlay_file.empty());
  EXPECT_GT(fs::file_size(s.overlay_file), 0u);
}

TEST(TrackSequence, EveryAndFramesSelectSourceIndices) {
  const fs::path seq = write_sequence("seq_range", 6);
  auto setup = make_setup();
  gtrack::TrackOptions opt;
  opt.input = (seq / "frames").string();
  opt.out_dir = seq / "out";
  opt.range = gtrack::parse_frame_range("1:6");
  opt.range.every = 2;
  opt.overlay = false;
  opt.progress = false;
  gtrack::track_sequence(setup, gtrack::engine_config(setup), opt);
  const auto csv = lines(opt.out_dir / "estimates.csv");
  ASSERT_EQ(csv.size(), 4u);
  EXPECT_EQ(csv[1].substr(0, 2), "1,");
  EXPECT_EQ(csv[2].substr(0, 2), "3,");
  EXPECT_EQ(csv[3].substr(0, 2), "5,");
}

TEST(TrackSequence, CancellationKeepsValidFiles) {
  const fs::path seq = write_sequence("seq_cancel", 5);
  auto setup = make_setup();
  std::atomic<bool> stop{false};
  gtrack::TrackOptions opt;
  opt.input = (seq / "frames").string();
  opt.out_dir = seq / "out";
  opt.progress = false;
  opt.cancel = &stop;
  opt.on_frame = [&](const gtrack::Estimate& e) {
    if (e.frame == 1) stop = true;
  };
  const auto s = gtrack::track_sequence(setup, gtrack::engine_config(setup), opt);
  EXPECT_TRUE(s.cancelled);
  EXPECT_EQ(s.frames, 2);
  EXPECT_EQ(lines(opt.out_dir / "estimates.csv").size(), 3u);
  EXPECT_EQ(lines(opt.out_dir / "estimates.jsonl").size(), 2u);
  const auto summary = lines(opt.out_dir / "summary.json");
  EXPECT_NE(std::find(summary.begin(), summary.end(), "  \"cancelled\": true,"), summary.end());
}

// SIGINT (Ctrl-C) or SIGHUP (the terminal closed) to a real `gtrack track`
// process: it finishes the frame, closes the files and exits with 130; every
// row written is complete, and the summary is written.
static void interrupt_leaves_complete_rows(int signal, const std::string& name, bool nohup = false) {
  const fs::path seq = write_sequence(name, 40);
  const fs::path cfg = seq / "config.toml";
  std::ofstream(cfg) << kConfig;
  const fs::path out = seq / "out";
  const std::string exe = std::string(GTRACK_TEST_BINARY_DIR) + "/bin/gtrack";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    if (nohup) ::signal(SIGHUP, SIG_IGN);  // as `nohup` starts it
    const std::string input = (seq / "frames").string(), outs = out.string(), cfgs = cfg.string(),
                      stim = (seq / "stimulus.csv").string();
    execl(exe.c_str(), exe.c_str(), "track", "--config", cfgs.c_str(), "--input", input.c_str(), "--stimulus",
          stim.c_str(), "--out", outs.c_str(), "--log-level", "warn", static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait for the second finished frame, then interrupt.
  const auto t0 = std::chrono::steady_clock::now();
  while (lines(out / "estimates.csv").size() < 3 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (nohup) {
    // Under nohup a closed terminal's SIGHUP changes nothing: the run goes on.
    kill(pid, SIGHUP);
    const auto t1 = std::chrono::steady_clock::now();
    while (lines(out / "estimates.csv").size() < 6 && std::chrono::steady_clock::now() - t1 < std::chrono::seconds(60)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    EXPECT_EQ(waitpid(pid, nullptr, WNOHANG), 0) << "the run stopped on a SIGHUP it was told to ignore";
  }
  kill(pid, signal);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const auto csv = lines(out / "estimates.csv");
  const auto jsonl = lines(out / "estimates.jsonl");
  EXPECT_GE(csv.size(), 3u);
  EXPECT_LT(csv.size(), 41u);
  EXPECT_EQ(jsonl.size() + 1, csv.size());
  for (size_t i = 1; i < csv.size(); ++i) EXPECT_EQ(fields(csv[i]), 17);
  for (const auto& j : jsonl) EXPECT_TRUE(j.front() == '{' && j.back() == '}') << j;
  EXPECT_TRUE(fs::exists(out / "summary.json"));
}

TEST(TrackCommand, SigintLeavesCompleteRows) { interrupt_leaves_complete_rows(SIGINT, "seq_sigint"); }
TEST(TrackCommand, SighupLeavesCompleteRows) { interrupt_leaves_complete_rows(SIGHUP, "seq_sighup"); }
TEST(TrackCommand, SighupUnderNohupIsIgnored) { interrupt_leaves_complete_rows(SIGINT, "seq_nohup", true); }

// --stream to a reader that has stopped reading: the run's write blocks
// once the pipe is full. Interrupted, it stops within a few seconds, files
// closed and summary written, instead of waiting for the reader forever.
TEST(TrackCommand, SigintWithAStalledStreamReaderStops) {
  const fs::path seq = write_sequence("seq_stalled", 300);
  const fs::path cfg = seq / "config.toml";
  std::ofstream(cfg) << kConfig;
  const fs::path out = seq / "out", err = seq / "err.txt";
  const std::string exe = std::string(GTRACK_TEST_BINARY_DIR) + "/bin/gtrack";
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::close(pipe_fds[0]);
    const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(e, STDERR_FILENO);
    const std::string input = (seq / "frames").string(), outs = out.string(), cfgs = cfg.string();
    execl(exe.c_str(), exe.c_str(), "track", "--config", cfgs.c_str(), "--input", input.c_str(), "--out", outs.c_str(),
          "--stream", "--no-overlay", "--log-level", "warn", static_cast<char*>(nullptr));
    _exit(127);
  }
  ::close(pipe_fds[1]);  // the pipe is never read: it fills, and the run's write blocks
  // Wait until the rows stop growing for 3 s: the write is blocked (a frame
  // takes a quarter of a second under the sanitizers on a loaded machine).
  size_t rows = 0;
  int still = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    const size_t now = lines(out / "estimates.csv").size();
    still = now == rows && now > 1 ? still + 1 : 0;
    if (still == 6 || std::chrono::steady_clock::now() - t0 > std::chrono::seconds(120)) break;
    rows = now;
  }
  ASSERT_LT(rows, 301u) << "the run ended before its stream's pipe filled";
  kill(pid, SIGINT);
  int status = 0;
  const auto t1 = std::chrono::steady_clock::now();
  while (waitpid(pid, &status, WNOHANG) == 0 && std::chrono::steady_clock::now() - t1 < std::chrono::seconds(30)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const bool stopped = std::chrono::steady_clock::now() - t1 < std::chrono::seconds(30);
  if (!stopped) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  ::close(pipe_fds[0]);
  ASSERT_TRUE(stopped) << "the run did not stop";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  std::ifstream in(err);
  const std::string said((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(said.find("interrupted, and the reader of --stream took no line for 5 s"), std::string::npos) << said;
}

// `gtrack synth` stopped part way (Ctrl-C) in the folder of an earlier
// sequence: the earlier sequence's truth is gone before any new frame is
// drawn, so no new frame is scored against it, and every frame written is
// whole.
TEST(SynthCommand, StoppedPartWayLeavesNoTruthBesideItsFrames) {
  const fs::path dir = temp_dir("synth_stopped");
  const std::string exe = std::string(GTRACK_TEST_BINARY_DIR) + "/bin/gtrack";
  const std::string out = (dir / "seq").string();
  ASSERT_EQ(std::system((exe + " synth --frames 2 --out " + out + " > /dev/null").c_str()), 0);
  ASSERT_TRUE(fs::exists(dir / "seq" / "ground_truth.csv"));
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl(exe.c_str(), exe.c_str(), "synth", "--frames", "300", "--seed", "7", "--threads", "1", "--out", out.c_str(),
          "--log-level", "warn", static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto t0 = std::chrono::steady_clock::now();
  while (!fs::exists(dir / "seq" / "frames" / "000003.png") &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(pid, SIGINT);
  waitpid(pid, nullptr, 0);
  EXPECT_FALSE(fs::exists(dir / "seq" / "ground_truth.csv"));
  int frames = 0;
  for (const auto& entry : fs::directory_iterator(dir / "seq" / "frames")) {
    if (entry.path().extension() != ".png") continue;
    ++frames;
    EXPECT_FALSE(cv::imread(entry.path().string()).empty()) << entry.path();
  }
  EXPECT_GE(frames, 4);
  EXPECT_LT(frames, 300);
}

TEST(TrackSequence, WrongImageSizeNamesFileAndSizes) {
  const fs::path dir = temp_dir("wrong_size");
  cv::imwrite((dir / "a.png").string(), cv::Mat(100, 120, CV_8UC3, cv::Scalar(0, 0, 0)));
  auto setup = make_setup();
  gtrack::TrackOptions opt;
  opt.input = dir.string();
  opt.out_dir = dir / "out";
  opt.progress = false;
  try {
    gtrack::track_sequence(setup, gtrack::engine_config(setup), opt);
    FAIL() << "expected InputError";
  } catch (const gtrack::InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("a.png"), std::string::npos) << m;
    EXPECT_NE(m.find("120x100"), std::string::npos) << m;
    EXPECT_NE(m.find("256x256"), std::string::npos) << m;
  }
}

TEST(TrackSequence, BadInputsAreInputErrors) {
  const fs::path dir = temp_dir("bad_inputs");
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  gtrack::TrackOptions opt;
  opt.out_dir = dir / "out";
  opt.progress = false;
  fs::create_directories(dir / "empty");
  opt.input = (dir / "empty").string();
  EXPECT_THROW(gtrack::track_sequence(setup, config, opt), gtrack::InputError);
  opt.input = (dir / "missing.mp4").string();
  EXPECT_THROW(gtrack::track_sequence(setup, config, opt), gtrack::InputError);
  std::ofstream(dir / "corrupt.avi") << "this is not a video";
  opt.input = (dir / "corrupt.avi").string();
  EXPECT_THROW(gtrack::track_sequence(setup, config, opt), gtrack::InputError);
  // An output folder below a regular file cannot be created.
  const fs::path seq = write_sequence("seq_unwritable", 1);
  std::ofstream(dir / "file") << "x";
  opt.input = (seq / "frames").string();
  opt.out_dir = dir / "file" / "out";
  EXPECT_THROW(gtrack::track_sequence(setup, config, opt), gtrack::InputError);
}

// [cost] occlusion_budget (on by default): the area the observation lacks
// compared with the model at the previous estimate is allowed as hidden, and
// the track holds its shape instead of shrinking onto the visible half.
TEST(Tracker, OcclusionBudgetHoldsAHalfHiddenGripper) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  ASSERT_DOUBLE_EQ(config.cost.occlusion_budget, 1.0);
  gtrack::Tracker tracker(setup, config);
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 30);
  tracker.set_estimate(truth);
  const auto clean = tracker.process(scene(setup, truth, 1), 0, 0.0, 26.0);
  EXPECT_DOUBLE_EQ(clean.outside_allowance, 0.0);
  const double full = static_cast<double>(clean.observed_pixels);
  for (int i = 1; i < 6; ++i) {
    const auto e = tracker.process(half_covered(tracker, setup, truth, i + 1), i, i / 30.0, 26.0);
    EXPECT_EQ(e.status, gtrack::TrackStatus::Tracked);
    // About half of the model is missing from O, and allowed for.
    EXPECT_GT(e.outside_allowance, 0.3 * full) << "frame " << i;
    EXPECT_LT(e.outside_allowance, 0.7 * full) << "frame " << i;
    // As good a fit as the truth's (which pays for its rim pixels along the
    // occluder's edge).
    EXPECT_LT(e.terms.dice, tracker.score(truth).dice + 0.01) << "frame " << i;
    EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.05) << "frame " << i;
    const double joints = (e.hypothesis.tail(6).array() - 30.0).abs().mean();
    EXPECT_LT(joints, 10.0) << "frame " << i << ": " << e.hypothesis.transpose();
  }
  // Off: the paper's D, no allowance; the true configuration of the half
  // hidden gripper then pays for its hidden half, and the track gives way.
  auto paper_config = config;
  paper_config.cost.occlusion_budget = 0;
  gtrack::Tracker paper(setup, paper_config);
  paper.set_estimate(truth);
  gtrack::Estimate p;
  for (int i = 1; i < 6; ++i) p = paper.process(half_covered(paper, setup, truth, i + 1), i, i / 30.0, 26.0);
  EXPECT_DOUBLE_EQ(p.outside_allowance, 0.0);
  EXPECT_GT(p.terms.dice, 0.1);
  // [cost] occlusion_tolerance: the share O may fall short of the model
  // before any of it is taken as hidden; at 0.8 half a gripper is not enough.
  auto tolerant_config = config;
  tolerant_config.cost.occlusion_tolerance = 0.8;
  gtrack::Tracker tolerant(setup, tolerant_config);
  tolerant.set_estimate(truth);
  const auto t = tolerant.process(half_covered(tolerant, setup, truth, 2), 1, 1 / 30.0, 26.0);
  EXPECT_DOUBLE_EQ(t.outside_allowance, 0.0);
}

// The budget's reference is the model's whole area, the part beyond the
// image's border included: a gripper coming into view under an occluder shows
// less of itself than the whole model, and the part the previous estimate had
// beyond the border has come in since. Taken from the in-view area alone, the
// allowance falls short of what is hidden (on the synthetic sequences the
// track then gave way to a compact wrong configuration; in this small scene
// it holds either way, so the allowance itself is what is checked).
TEST(Tracker, OcclusionBudgetCountsThePartBeyondTheBorder) {
  auto setup = make_setup();
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  // The same model on a canvas with a 64-pixel margin around the image.
  gtrack::RenderOptions ro;
  ro.backend = "cpu";
  auto padded = gtrack::make_cpu_renderer(ro);
  padded->set_model(setup.model());
  padded->set_projection(gtrack::padded_projection(setup.sensor->projection(), 64, 64), 0.5);
  // Nearly flat, its palm centre 96 px from the image's centre: the tips of
  // the right-hand fingers are beyond the right border.
  Eigen::VectorXd truth = pose(3.0, -0.2, 20, 2);
  ASSERT_GT(cv::countNonZero(padded->render_mask(truth)),
            cv::countNonZero(tracker.renderer().render_mask(truth)) + 100);
  tracker.set_estimate(truth);
  ASSERT_EQ(tracker.process(scene(setup, truth, 1), 0, 0.0, 22.0).status, gtrack::TrackStatus::Tracked);
  for (int i = 1; i < 6; ++i) {
    const Eigen::VectorXd previous = tracker.last_estimate().value();
    const double whole = cv::countNonZero(padded->render_mask(previous));
    truth[0] -= 0.1;  // coming into view, its left half hidden
    const auto e = tracker.process(half_covered(tracker, setup, truth, i + 1), i, i / 30.0, 22.0);
    EXPECT_EQ(e.status, gtrack::TrackStatus::Tracked);
    // All that O lacks of the previous model's whole area is allowed for,
    // the part that was beyond the border included.
    EXPECT_DOUBLE_EQ(e.outside_allowance, whole - static_cast<double>(e.observed_pixels)) << "frame " << i;
    EXPECT_LT(e.terms.dice, tracker.score(truth).dice + 0.01) << "frame " << i;
    EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.05) << "frame " << i;
    const double joints = (e.hypothesis.tail(6).array() - 2.0).abs().mean();
    EXPECT_LT(joints, 10.0) << "frame " << i << ": " << e.hypothesis.transpose();
  }
}

// Tracker::score (gtrack track --score-truth): a configuration scored after
// a frame gets exactly the terms the estimate got, allowance and temporal
// term included, and another configuration scores worse.
TEST(Tracker, ScoreRepeatsTheFramesCost) {
  auto setup = make_setup();
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 30);
  EXPECT_THROW(tracker.score(truth), gtrack::Error);  // no frame yet
  tracker.set_estimate(truth);
  // Each frame's terms are its estimate's (kept from the search's own
  // batches, not rendered again).
  for (int i = 0; i < 2; ++i) {
    const auto f = tracker.process(scene(setup, truth, 1 + i), i, i / 30.0, 26.0);
    const gtrack::CostTerms scored = tracker.score(f.hypothesis);
    EXPECT_DOUBLE_EQ(scored.total, f.terms.total) << "frame " << i;
    EXPECT_EQ(scored.rendered, f.terms.rendered) << "frame " << i;
    EXPECT_EQ(scored.overlap, f.terms.overlap) << "frame " << i;
  }
  const auto e = tracker.process(half_covered(tracker, setup, truth, 3), 2, 2 / 30.0, 26.0);
  ASSERT_GT(e.outside_allowance, 0.0);  // the budget is part of what is repeated
  ASSERT_GT(e.terms.temporal, 0.0);     // and the temporal term
  const gtrack::CostTerms again = tracker.score(e.hypothesis);
  EXPECT_DOUBLE_EQ(again.total, e.terms.total);
  EXPECT_DOUBLE_EQ(again.dice, e.terms.dice);
  EXPECT_DOUBLE_EQ(again.temporal, e.terms.temporal);
  EXPECT_EQ(again.rendered, e.terms.rendered);
  EXPECT_EQ(again.overlap, e.terms.overlap);
  EXPECT_EQ(again.rim, e.terms.rim);
  EXPECT_GT(again.rim, 0u);                  // along the occluder's edge
  EXPECT_GT(again.rendered, again.overlap);  // half of it is hidden
  Eigen::VectorXd off = e.hypothesis;
  off[0] += 0.3;
  EXPECT_GT(tracker.score(off).total, e.terms.total + 0.05);
  EXPECT_THROW(tracker.score(e.hypothesis.head(8)), gtrack::Error);
}

// Tracker::score_after (the two-pass path): the allowance is the one a track
// with that previous estimate would have had. After the track's own previous
// estimate it repeats score(); after a previous estimate seen edge-on (a far
// smaller area) the half-hidden truth gets no allowance and pays for its
// hidden half; the tracker's own allowance is left as it was.
TEST(Tracker, ScoreAfterTakesTheAllowanceOfAnotherPreviousEstimate) {
  auto setup = make_setup();
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 30);
  tracker.set_estimate(truth);
  tracker.process(scene(setup, truth, 1), 0, 0.0, 26.0);
  const Eigen::VectorXd previous = tracker.last_estimate().value();
  const auto e = tracker.process(half_covered(tracker, setup, truth, 2), 1, 1 / 30.0, 26.0);
  ASSERT_GT(e.outside_allowance, 0.0);
  const gtrack::CostTerms own = tracker.score(truth);
  const gtrack::CostTerms after_own = tracker.score_after(truth, previous);
  EXPECT_DOUBLE_EQ(after_own.total, own.total);
  EXPECT_DOUBLE_EQ(after_own.dice, own.dice);
  Eigen::VectorXd edge_on = previous;
  edge_on[3] = 85;  // tilted nearly edge-on: its whole area is far below O's
  const gtrack::CostTerms after_edge_on = tracker.score_after(truth, edge_on);
  EXPECT_GT(after_edge_on.dice, own.dice + 0.1);
  EXPECT_DOUBLE_EQ(tracker.score(truth).total, own.total);  // the tracker's own allowance is back
  EXPECT_THROW(tracker.score_after(truth, previous.head(8)), gtrack::Error);
}

// [cost] occlusion_rim_px: under an occluder, a model larger than the truth
// that covers what is visible spills within the budget's allowance; only the
// rim, the ring just outside O, tells it from the truth.
TEST(Tracker, TheRimMakesALooseModelPayUnderAnOccluder) {
  auto setup = make_setup();
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 30);
  Eigen::VectorXd loose = truth;
  loose[2] -= 4;  // 4 % nearer the camera: the same outline, 8 % more area
  double gap[2] = {0, 0};
  for (int rim : {0, 1}) {
    auto config = gtrack::engine_config(setup);
    config.cost.occlusion_rim_px = rim;
    gtrack::Tracker tracker(setup, config);
    tracker.set_estimate(truth);
    tracker.process(scene(setup, truth, 1), 0, 0.0, 26.0);
    tracker.process(scene(setup, truth, 2), 1, 1 / 30.0, 26.0);
    const auto e = tracker.process(half_covered(tracker, setup, truth, 3), 2, 2 / 30.0, 26.0);
    ASSERT_GT(e.outside_allowance, 0.0);
    gap[rim] = tracker.score(loose).dice - tracker.score(truth).dice;
  }
  // The budget alone: nearly as good as the truth (0.005 here). With the rim
  // the gap doubles (0.011): the loose model's spill along the visible
  // outline is no longer taken as hidden.
  EXPECT_LT(gap[0], 0.008);
  EXPECT_GT(gap[1], gap[0] + 0.004);
}

// [tracker] redetect_dice: a track that sits on a wrong configuration while
// the gripper is in plain view is replaced by the coarse search's result.
TEST(Tracker, RedetectionReplacesAWrongTrack) {
  auto setup = make_setup();
  auto config = gtrack::engine_config(setup);
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 30);
  Eigen::VectorXd wrong = pose(0.9, 0.3, 45, 0);
  wrong[3] = -20;
  const cv::Mat img = scene(setup, truth, 3);
  {
    gtrack::Tracker tracker(setup, config);
    tracker.set_estimate(wrong);
    const auto e = tracker.process(img, 0, 0.0, 26.0);
    EXPECT_TRUE(e.redetected);
    EXPECT_EQ(e.status, gtrack::TrackStatus::Tracked);
    EXPECT_LT(e.terms.dice, 0.05);
    EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.05) << e.hypothesis.transpose();
  }
  {
    config.tracker.redetect_dice = 1.0;  // the paper's tracker: never
    config.tracker.refine_spread = 0;    // nor a refinement (which alone brings this track to 0.05 mm)
    gtrack::Tracker tracker(setup, config);
    tracker.set_estimate(wrong);
    const auto e = tracker.process(img, 0, 0.0, 26.0);
    EXPECT_FALSE(e.redetected);
    EXPECT_GT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.1) << e.hypothesis.transpose();
  }
}

// Re-detection looks at the whole image: a track 2 mm off has its ROI and
// prior around the wrong place, which cut away most of the gripper.
TEST(Tracker, RedetectionSearchesTheWholeImage) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 30);
  const Eigen::VectorXd wrong = pose(2.3, -0.2, 20, 30);
  const cv::Mat img = scene(setup, truth, 5);
  gtrack::Tracker fresh(setup, config);
  const std::uint64_t whole = fresh.process(img, 0, 0.0, 26.0).observed_pixels;
  gtrack::Tracker tracker(setup, config);
  tracker.set_estimate(wrong);
  const auto e = tracker.process(img, 0, 0.0, 26.0);
  EXPECT_TRUE(e.redetected);
  EXPECT_EQ(e.observed_pixels, whole);
  EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.05) << e.hypothesis.transpose();
}

// [tracker] mirror_check: a track that starts on the mirror tilt of a folded,
// tilted gripper crosses to the right one in a frame.
TEST(Tracker, MirrorCheckLeavesTheMirrorTilt) {
  auto setup = make_setup();
  auto config = gtrack::engine_config(setup);
  config.tracker.mirror_particles = 0;  // the check on its own
  config.tracker.redetect_dice = 1.0;
  config.cost.temporal = 0;  // (no prediction particle either)
  Eigen::VectorXd truth = pose(0.3, -0.2, 20, 40);
  truth[3] = 25;
  truth[4] = 0;
  Eigen::VectorXd mirror = truth;
  mirror[3] = -25;
  const cv::Mat img = scene(setup, truth, 4);  // 26 C: in the transition, 40 deg is allowed
  gtrack::Tracker tracker(setup, config);
  tracker.set_estimate(mirror);
  const auto e = tracker.process(img, 0, 0.0, 26.0);
  EXPECT_TRUE(e.mirrored) << "D " << e.terms.dice << " redetected " << e.redetected;
  EXPECT_NEAR(e.hypothesis[3], 25.0, 8.0) << e.hypothesis.transpose();
  EXPECT_LT((e.hypothesis.head<2>() - truth.head<2>()).norm(), 0.05) << e.hypothesis.transpose();
  // Without it the swarm stays on the mirror branch.
  config.tracker.mirror_check = false;
  gtrack::Tracker plain(setup, config);
  plain.set_estimate(mirror);
  const auto p = plain.process(img, 0, 0.0, 26.0);
  EXPECT_FALSE(p.mirrored);
  EXPECT_LT(p.hypothesis[3], 0.0) << p.hypothesis.transpose();
  EXPECT_FALSE(p.tilt_margin.has_value()) << "no check, no margin";
}

// Estimate::tilt_margin says how sure the tilt's sign is. A folded gripper
// tilted by 25 deg shows its tilt in its outline: its mirror scores far
// worse. A flat one casts nearly the outline of its mirror: the margin is
// narrow. A gripper seen flat-on is not checked: its mirror is itself.
TEST(Tracker, TiltMarginIsWideForAFoldedGripperAndNarrowForAFlatOne) {
  auto setup = make_setup();
  auto config = gtrack::engine_config(setup);
  config.tracker.redetect_dice = 1.0;
  const auto margin = [&](double tilt, double fold) {
    Eigen::VectorXd truth = pose(0.3, -0.2, 20, fold);
    truth[3] = tilt;
    truth[4] = 0;
    gtrack::Tracker tracker(setup, config);
    tracker.set_estimate(truth);
    const auto e = tracker.process(scene(setup, truth, 4), 0, 0.0, fold > 0 ? 26.0 : 22.0);
    EXPECT_EQ(e.status, gtrack::TrackStatus::Tracked);
    return e.tilt_margin;
  };
  const auto folded = margin(25, 40), flat = margin(25, 0), flat_on = margin(0, 0);
  ASSERT_TRUE(folded.has_value());
  ASSERT_TRUE(flat.has_value());
  // (Measured: 2.17 and 0.10. On a frame this clean the costs are small,
  // and the flat mirror's few pixels of perspective and its shorter swarm
  // are a tenth of them.)
  EXPECT_GT(*folded, 0.5);
  EXPECT_LT(*flat, 0.25);
  EXPECT_LT(*flat, *folded / 5);
  if (flat_on) {
    ADD_FAILURE() << "a gripper seen flat-on was checked (margin " << *flat_on << ")";
  }
  // The overlay says so at its top under a narrow margin only.
  Eigen::VectorXd h = pose(0.3, -0.2, 20, 0);
  h[3] = 25;
  const cv::Mat image = scene(setup, h, 4);
  gtrack::Tracker tracker(setup, config);
  gtrack::Estimate e;
  e.hypothesis = h;
  const cv::Rect corner(0, 0, image.cols, image.rows / 8);  // the top band
  const cv::Mat none = tracker.draw_overlay(image, e);
  e.tilt_margin = 0.5;
  const cv::Mat wide = tracker.draw_overlay(image, e);
  e.tilt_margin = 0.05;
  const cv::Mat narrow = tracker.draw_overlay(image, e);
  EXPECT_EQ(cv::norm(none(corner), wide(corner), cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(none(corner), narrow(corner), cv::NORM_L1), 0);
  cv::Mat diff, changed;
  cv::absdiff(none, narrow, diff);
  cv::transform(diff, changed, cv::Matx13f(1, 1, 1));  // summed over the channels
  std::vector<cv::Point> at;
  cv::findNonZero(changed, at);
  ASSERT_FALSE(at.empty());
  const cv::Rect where = cv::boundingRect(at);
  EXPECT_EQ(where & corner, where) << where;  // nothing else drawn
}

// The overlay's outline lies where the renderers put the model: its filled
// area's centre is the rendered mask's, within a quarter of a pixel
// (measured: 0.13 px, the anti-aliased outline's share on this small image).
// It had been drawn half a pixel down and right (0.58 and 0.42 px), OpenCV's
// pixel centres being on integers and gtrack's at +0.5.
TEST(Tracker, TheOverlayIsDrawnWhereTheModelIsRendered) {
  auto setup = make_setup();
  const Eigen::VectorXd h = pose(0.3, -0.2, 20, 30);
  const cv::Mat mask = rendered_mask(setup, h);
  gtrack::Tracker tracker(setup, gtrack::engine_config(setup));
  gtrack::Estimate e;
  e.hypothesis = h;
  const cv::Mat black(mask.size(), CV_8UC3, cv::Scalar::all(0));
  cv::Mat drawn;
  cv::extractChannel(tracker.draw_overlay(black, e), drawn, 1);  // green
  drawn(cv::Rect(0, 0, drawn.cols, drawn.rows / 8)).setTo(0);    // the reading's text
  drawn(cv::Rect(0, drawn.rows * 7 / 8, drawn.cols, drawn.rows / 8)).setTo(0);
  const cv::Moments m = cv::moments(mask, true), o = cv::moments(drawn, false);
  ASSERT_GT(m.m00, 100);
  ASSERT_GT(o.m00, 0);
  EXPECT_NEAR(o.m10 / o.m00, m.m10 / m.m00, 0.25);
  EXPECT_NEAR(o.m01 / o.m00, m.m01 / m.m00, 0.25);
}

// The turned tilt of re-detection's searches: the Euler pair (rx, ry)
// turned in its plane, the rest of the configuration unchanged; 180 deg is
// the mirror.
TEST(Model, TiltTurnedTurnsTheEulerPairAndKeepsTheRest) {
  Eigen::VectorXd h = pose(0.3, -0.2, 20, 40);
  h[3] = 30;
  h[4] = 10;
  const Eigen::VectorXd m = gtrack::tilt_turned(h, 180);
  EXPECT_NEAR(m[3], -30, 1e-9);
  EXPECT_NEAR(m[4], -10, 1e-9);
  Eigen::VectorXd t = h;
  for (int k = 0; k < 6; ++k) {
    t = gtrack::tilt_turned(t, 60);
    EXPECT_NEAR(std::hypot(t[3], t[4]), std::hypot(30.0, 10.0), 1e-9);
    EXPECT_EQ(t.segment(5, 7), h.segment(5, 7));
    EXPECT_EQ(t.head<3>(), h.head<3>());
  }
  EXPECT_NEAR((t - h).norm(), 0.0, 1e-9);
  const Eigen::VectorXd q = gtrack::tilt_turned(h, 90);
  EXPECT_NEAR(q[3], -10, 1e-9);
  EXPECT_NEAR(q[4], 30, 1e-9);
}

// [tracker] redetect_tilt_directions: re-detection also searches from the
// track with its tilt turned by 60, 120, ... 300 deg, each search a short
// CMA-ES (N/2 samples, G/3 generations), and keeps what scores lowest. Here
// the track's tilt points 120 deg away from the truth's. (In plain view the
// coarse search finds this gripper too; the searches matter under large
// occluders, docs/RESULTS.md.)
TEST(Tracker, RedetectionTriesTheTiltTurned) {
  auto setup = make_setup();
  auto config = gtrack::engine_config(setup);
  EXPECT_EQ(config.tracker.redetect_tilt_directions, 0);  // the engine's default: none
  config.tracker.mirror_check = false;
  config.tracker.refine_spread = 0;
  Eigen::VectorXd truth = pose(0.3, -0.2, 20, 40);
  truth[3] = 45;
  truth[4] = 0;
  const Eigen::VectorXd wrong = gtrack::tilt_turned(truth, 120);
  const cv::Mat img = scene(setup, truth, 6);  // 26 C: in the transition, 40 deg is allowed
  gtrack::Estimate e[2];
  for (int directions : {0, 6}) {
    config.tracker.redetect_tilt_directions = directions;
    gtrack::Tracker tracker(setup, config);
    tracker.set_estimate(wrong);
    e[directions > 0] = tracker.process(img, 0, 0.0, 26.0);
  }
  // Up to re-detection the two frames are the same; then five searches of
  // 16 x 8 more, whose best is kept only if it scores lower.
  EXPECT_EQ(e[1].evaluations, e[0].evaluations + 5 * 16 * 8);
  EXPECT_TRUE(e[1].redetected);
  EXPECT_LE(e[1].terms.total, e[0].terms.total);
  EXPECT_LT(std::hypot(e[1].hypothesis[3] - truth[3], e[1].hypothesis[4] - truth[4]), 12.0)
      << e[1].hypothesis.transpose();
  for (const char* bad : {"-1", "37", "2.5"}) {
    const std::string m = engine_config_error(std::string("[tracker]\nredetect_tilt_directions = ") + bad + "\n");
    EXPECT_NE(m.find("redetect_tilt_directions"), std::string::npos) << m;
  }
}

// [tracker] refine_spread: the refinement swarm runs last, on the same random
// stream, so up to it a frame is the unrefined tracker's; it adds N x G
// evaluations and keeps its result only when that scores lower. A swarm too
// short to settle (N = 8, G = 3) leaves it something to find.
TEST(Tracker, TheRefinementOnlyEverLowersTheCost) {
  auto setup = make_setup();
  auto config = gtrack::engine_config(setup);
  config.pso.particles = 8;
  config.pso.generations = 3;
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 30);
  Eigen::VectorXd start = truth;
  start[0] += 0.06;
  start[5] += 4;
  const cv::Mat img = scene(setup, truth, 11);
  config.tracker.refine_spread = 0;
  gtrack::Tracker plain(setup, config);
  plain.set_estimate(start);
  const auto a = plain.process(img, 0, 0.0, 26.0);
  for (const char* optimizer : {"cmaes", "pso"}) {
    config.tracker.refine_spread = 0.25;
    config.tracker.refine_optimizer = optimizer;
    gtrack::Tracker refined(setup, config);
    refined.set_estimate(start);
    const auto b = refined.process(img, 0, 0.0, 26.0);
    EXPECT_EQ(b.evaluations, a.evaluations + 8 * 3) << optimizer;
    EXPECT_LT(b.terms.total, a.terms.total) << optimizer;
    EXPECT_DOUBLE_EQ(refined.score(b.hypothesis).total, b.terms.total) << optimizer;
  }
  for (const char* bad : {"-0.5", "\"wide\""}) {
    auto s = make_setup(std::string("[tracker]\nrefine_spread = ") + bad + "\n");
    EXPECT_THROW(gtrack::engine_config(s), gtrack::ConfigError) << bad;
  }
}

// [tracker] unseen_joint_tolerance: under an occluder that hides the left
// half of the gripper, the fingers there do not change what is rendered
// inside O, and the track leaves their joints wherever it started them. The
// estimate reports them at the seen fingers' mean fold; the pose, the seen
// fingers and the track's own state stay the search's result.
TEST(Tracker, UnseenFingersTakeTheSeenFingersFold) {
  auto setup = make_setup();
  const Eigen::VectorXd truth = pose(0.3, -0.2, 20, 30);
  Eigen::VectorXd start = truth;
  start.tail(6) << 10, 50, 10, 50, 10, 50;  // every finger 20 deg off
  const auto joint_error = [&](const Eigen::VectorXd& h) { return (h.tail(6).array() - 30.0).abs().mean(); };
  const auto track = [&](double tolerance) {
    auto config = gtrack::engine_config(setup);
    config.tracker.unseen_joint_tolerance = tolerance;
    auto tracker = std::make_unique<gtrack::Tracker>(setup, config);
    tracker->set_estimate(start);
    gtrack::Estimate e;
    // No stimulus: nothing but the image and the fingers' neighbours
    // decides a joint.
    for (int i = 1; i < 4; ++i) {
      e = tracker->process(half_covered(*tracker, setup, truth, i + 1), i, i / 30.0, std::nullopt);
    }
    return std::make_pair(std::move(tracker), e);
  };
  const auto [off_tracker, off] = track(0);
  const auto [on_tracker, on] = track(0.001);
  EXPECT_EQ(on.status, gtrack::TrackStatus::Tracked);
  // The search left the fingers off (the hidden ones most), and the fill
  // brings the reported joints nearer the truth.
  EXPECT_GT(joint_error(off.hypothesis), 4.0) << off.hypothesis.transpose();
  EXPECT_LT(joint_error(on.hypothesis), joint_error(off.hypothesis) - 1.0) << on.hypothesis.transpose();
  // The fill changes joints only, costs at most the tolerance, and the track
  // goes on from the search's own result: the same as without the fill.
  const Eigen::VectorXd state = *on_tracker->last_estimate();
  EXPECT_EQ(state, off.hypothesis);
  EXPECT_EQ(on.hypothesis.head<6>(), state.head<6>());
  EXPECT_NE(on.hypothesis.tail(6), state.tail(6));
  EXPECT_LE(on.terms.total, on_tracker->score(state).total + 0.001);
  EXPECT_DOUBLE_EQ(on_tracker->score(on.hypothesis).total, on.terms.total);
  // Filled fingers share one value, the seen fingers' mean.
  const Eigen::VectorXd q = on.hypothesis.tail(6), s = state.tail(6);
  int filled = 0;
  double seen_sum = 0;
  for (int k = 0; k < 6; ++k) {
    if (q[k] != s[k]) {
      ++filled;
    } else {
      seen_sum += s[k];
    }
  }
  ASSERT_GT(filled, 0);
  ASSERT_LT(filled, 6);
  EXPECT_TRUE(off.unseen_fingers.empty());
  ASSERT_EQ(on.unseen_fingers.size(), static_cast<std::size_t>(filled));
  for (int f : on.unseen_fingers) EXPECT_NE(q[f - 1], s[f - 1]) << "finger " << f;
  for (int k = 0; k < 6; ++k) {
    if (q[k] != s[k]) EXPECT_NEAR(q[k], seen_sum / (6 - filled), 1e-9) << k;
  }
  // A lost frame after it reports what that frame reported, filled joints
  // and all (a controller holding the estimate sees no jump), while the
  // track still holds the search's result; a resumed tracker does the same.
  const cv::Mat empty(setup.sensor->image_size().height, setup.sensor->image_size().width, CV_8UC3,
                      cv::Scalar(120, 125, 130));
  gtrack::Tracker resumed(setup, on_tracker->config());
  resumed.restore(gtrack::parse_tracker_state(
      [&] {
        const auto file = std::filesystem::temp_directory_path() /
                          ("gtrack_reported_state_" + std::to_string(::getpid()) + ".txt");
        gtrack::write_tracker_state(file, on_tracker->state());
        std::ifstream in(file);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::filesystem::remove(file);
        return text;
      }(),
      "state"));
  for (gtrack::Tracker* t : {on_tracker.get(), &resumed}) {
    const gtrack::Estimate lost = t->process(empty, 4, 4 / 30.0, std::nullopt);
    ASSERT_EQ(lost.status, gtrack::TrackStatus::Lost);
    EXPECT_TRUE(lost.hypothesis.isApprox(on.hypothesis, 1e-12)) << lost.hypothesis.transpose();
    EXPECT_TRUE(t->last_estimate()->isApprox(state, 1e-12));
  }
  for (const char* bad : {"-0.001", "2.0", "\"small\""}) {
    const std::string m = engine_config_error(std::string("[tracker]\nunseen_joint_tolerance = ") + bad + "\n");
    EXPECT_NE(m.find("unseen_joint_tolerance"), std::string::npos) << m;
    EXPECT_NE(m.find("<test>:"), std::string::npos) << m;
  }
}

// [observation] exclude_px: rectangles of whole pixels within the image.
TEST(EngineConfig, ExcludedRectanglesAreWholePixelsWithinTheImage) {
  auto setup = make_setup("[observation]\nexclude_px = [[0, 240, 60, 16], [200, 0, 56, 20]]\n");
  const auto c = gtrack::engine_config(setup);
  ASSERT_EQ(c.observation.exclude_px.size(), 2u);
  EXPECT_EQ(c.observation.exclude_px[0], cv::Rect(0, 240, 60, 16));
  EXPECT_TRUE(gtrack::engine_config(make_setup()).observation.exclude_px.empty());
  for (const char* bad : {"[[0, 250, 60, 16]]", "[[0, 0, 0, 5]]", "[[1.5, 0, 4, 4]]", "[[0, 0, 4]]"}) {
    const std::string m = engine_config_error(std::string("[observation]\nexclude_px = ") + bad + "\n");
    EXPECT_NE(m.find("<test>:"), std::string::npos) << m;
    EXPECT_NE(m.find("exclude_px"), std::string::npos) << m;
  }
  EXPECT_NE(engine_config_error("[observation]\nexclude_px = [[0, 250, 60, 16]]\n")
                .find("expected [x, y, width, height] in whole pixels, width and height at least 1, within the "
                      "256x256 image"),
            std::string::npos);
}

// Values inside a key's old range that broke the track without a word: a
// sigma whose square underflows (costs of nan on frames said ok), a margin
// past an int (every frame after the first lost), weights that overflow the
// tables. Each is refused naming its key and the range.
TEST(EngineConfig, ValuesThatWouldBreakTheCostOrTheSearchBoxAreRefused) {
  for (const auto& [extra, said] : std::vector<std::pair<std::string, std::string>>{
           {"[cost]\ncoherence_sigma_deg = 1e-300\n", "key 'cost.coherence_sigma_deg'"},
           {"[cost]\ntemporal_joint_sigma_deg = 1e-9\n", "expected 0 (the joints left out) or a number in [0.01, 180]"},
           {"[cost]\nlambda_dice = 1e308\n", "key 'cost.lambda_dice'"},
           {"[cost]\nlambda_temporal = 1e7\n", "key 'cost.lambda_temporal'"},
           {"[observation]\nroi_margin_px = 2.2e9\n", "key 'observation.roi_margin_px'"},
           {"[pso]\nc = 1e300\n", "key 'pso.c'"},
           {"[tracker]\ninit_spread = [0.1, 0.1, 1e-300, 10, 10, 10, 10]\n", "value 1e-300 for z is out of range"},
           {"[tracker]\ninit_spread = [0.1, 0.1, 0.1, 10, 10, 1e9, 10]\n", "key 'tracker.init_spread[5]'"}}) {
    const std::string m = engine_config_error(extra);
    EXPECT_NE(m.find(said), std::string::npos) << extra << m;
  }
  EXPECT_NO_THROW(gtrack::engine_config(make_setup("[cost]\ntemporal_joint_sigma_deg = 0\n")));
  EXPECT_NO_THROW(gtrack::engine_config(make_setup("[tracker]\ninit_spread = [0.1, 0.1, 0, 10, 10, 10, 0]\n")));
}

// [render] egl_device's form is checked with the config, naming its key:
// the gl backend's own message named a C++ member.
TEST(EngineConfig, TheEglDeviceIsAnIndexOrSurfaceless) {
  const auto config = [](const std::string& device) {
    std::string text = kConfig;
    text.replace(text.find("threads = 2\n"), 12, "threads = 2\negl_device = " + device + "\n");
    return gtrack::engine_config(gtrack::load_setup(gtrack::ConfigTable::parse(text, "<test>"), {}));
  };
  for (const char* good : {"\"\"", "\"0\"", "\"12\"", "\"surfaceless\""}) {
    EXPECT_NO_THROW(config(good)) << good;
  }
  for (const char* bad : {"\"foo\"", "\"-1\""}) {
    try {
      config(bad);
      ADD_FAILURE() << bad << " was taken";
    } catch (const gtrack::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("key 'render.egl_device': '"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("expected a device index (0, 1, ...)"), std::string::npos) << e.what();
    }
  }
}

TEST(EngineConfig, PaperDefaults) {
  auto setup = make_setup();
  const auto c = gtrack::engine_config(setup);
  EXPECT_EQ(c.pso.particles, 32);
  EXPECT_EQ(c.pso.generations, 25);
  EXPECT_DOUBLE_EQ(c.pso.inertia, 0.4);
  EXPECT_DOUBLE_EQ(c.pso.c, 1.0);
  EXPECT_EQ(c.pso.randomize_every, 8);
  EXPECT_DOUBLE_EQ(c.cost.dice, 2.0);
  EXPECT_DOUBLE_EQ(c.cost.kinematic, 0.15);
  EXPECT_DOUBLE_EQ(c.cost.stimulus, 1.0);
  EXPECT_DOUBLE_EQ(c.cost.occlusion_discount, 0.0);  // paper
  // Additions on by default (docs/tracker.md); each has a value that turns it off.
  EXPECT_DOUBLE_EQ(c.cost.temporal, 0.001);  // lambda_temporal; 0 = paper
  EXPECT_DOUBLE_EQ(c.cost.temporal_joint_sigma_deg, 3.0);  // 0 = joints left out of T
  EXPECT_DOUBLE_EQ(c.cost.coherence, 0.0);  // lambda_coherence: paper (the metallic configs set 0.003)
  EXPECT_DOUBLE_EQ(c.cost.coherence_sigma_deg, 10.0);
  EXPECT_DOUBLE_EQ(c.cost.occlusion_budget, 1.0);
  EXPECT_DOUBLE_EQ(c.cost.occlusion_tolerance, 0.05);
  EXPECT_DOUBLE_EQ(c.cost.occlusion_growth_weight, 0.1);
  EXPECT_EQ(c.cost.occlusion_rim_px, 3);
  EXPECT_DOUBLE_EQ(gtrack::RenderOptions{}.scale, 0.5);  // paper: 0.25
  EXPECT_DOUBLE_EQ(c.tracker.redetect_dice, 0.01);
  EXPECT_TRUE(c.tracker.mirror_check);
  EXPECT_DOUBLE_EQ(c.tracker.refine_spread, 0.25);  // 0 = no refinement swarm
  EXPECT_TRUE(c.tracker.coarse_wide_tilts);
  EXPECT_DOUBLE_EQ(c.tracker.unseen_joint_tolerance, 0.001);  // 0 = joints reported as searched
  // Depth spread: a quarter of the in-plane one (model radius 2 mm).
  EXPECT_NEAR(c.tracker.init_spread[2], 0.25 * c.tracker.init_spread[0], 1e-12);
  EXPECT_EQ(c.space.dims(), 12);
  EXPECT_TRUE(c.space.periodic[5]);
}

TEST(EngineConfig, UnknownKeyNamesFileLineAndSuggestion) {
  const std::string m = engine_config_error("[pso]\nparticels = 16\n");
  EXPECT_NE(m.find("particels"), std::string::npos) << m;
  EXPECT_NE(m.find("particles"), std::string::npos) << m;
  EXPECT_NE(m.find("<test>:"), std::string::npos) << m;
}

TEST(EngineConfig, UnknownTableIsAnError) {
  auto setup = make_setup("[tracer]\nfps = 10\n");
  gtrack::engine_config(setup);
  EXPECT_THROW(gtrack::check_root_keys(setup), gtrack::ConfigError);
}

TEST(EngineConfig, CoherenceKeysAreReadAndChecked) {
  const auto c = gtrack::engine_config(make_setup("[cost]\nlambda_coherence = 0.003\ncoherence_sigma_deg = 4\n"));
  EXPECT_DOUBLE_EQ(c.cost.coherence, 0.003);
  EXPECT_DOUBLE_EQ(c.cost.coherence_sigma_deg, 4.0);
  for (const char* bad : {"lambda_coherence = -1", "coherence_sigma_deg = 0", "coherence_sigma_deg = 200",
                          "lambda_coherence = \"high\""}) {
    auto s = make_setup(std::string("[cost]\n") + bad + "\n");
    EXPECT_THROW(gtrack::engine_config(s), gtrack::ConfigError) << bad;
  }
}

TEST(EngineConfig, TheRefinementOptimiserIsCmaesOrPso) {
  EXPECT_EQ(gtrack::engine_config(make_setup("")).tracker.refine_optimizer, "cmaes");
  EXPECT_EQ(gtrack::engine_config(make_setup("[tracker]\nrefine_optimizer = \"pso\"\n")).tracker.refine_optimizer,
            "pso");
  for (const char* bad : {"\"cma\"", "1", "true"}) {
    const std::string m = engine_config_error(std::string("[tracker]\nrefine_optimizer = ") + bad + "\n");
    EXPECT_NE(m.find("refine_optimizer"), std::string::npos) << m;
  }
}

TEST(EngineConfig, TheRimIsAWholeNumberOfPixels) {
  EXPECT_EQ(gtrack::engine_config(make_setup("[cost]\nocclusion_rim_px = 0\n")).cost.occlusion_rim_px, 0);
  EXPECT_EQ(gtrack::engine_config(make_setup("[cost]\nocclusion_rim_px = 3\n")).cost.occlusion_rim_px, 3);
  for (const char* bad : {"1.5", "-1", "17", "\"one\""}) {
    const std::string m = engine_config_error(std::string("[cost]\nocclusion_rim_px = ") + bad + "\n");
    EXPECT_NE(m.find("occlusion_rim_px"), std::string::npos) << m;
    EXPECT_NE(m.find("<test>:"), std::string::npos) << m;
  }
}

TEST(EngineConfig, InitialPoseMustHaveEveryParameter) {
  auto setup = make_setup("[tracker]\ninitial_pose = [0.0, 0.0, 100.0]\n");
  EXPECT_THROW(gtrack::engine_config(setup), gtrack::ConfigError);
}

// For a sensor turned in the world, [search] positions and initial_pose are
// read in the world and taken into the sensor's frame, where the tracker
// searches: the box becomes the box about its corners there.
TEST(EngineConfig, ATurnedSensorsBoxAndInitialPoseAreTakenIntoItsFrame) {
  const auto setup = gtrack::testing::probe_setup(
      "[-90, 0, 0]",
      "[search]\nposition_min_mm = [-1.0, -2.0, -30.0]\nposition_max_mm = [1.0, 2.0, -20.0]\n[tracker]\n"
      "initial_pose = [0.5, 1.0, -25.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n");
  const auto config = gtrack::engine_config(setup);
  const gtrack::SensorFrame frame = gtrack::sensor_frame(*setup.sensor);
  ASSERT_FALSE(frame.is_world());
  // The box's extents along the probe's lateral, depth and elevation axes:
  // world x, -z and y.
  const Eigen::Vector3d extent = config.space.upper.head<3>() - config.space.lower.head<3>();
  EXPECT_LT((extent - Eigen::Vector3d(2, 10, 4)).norm(), 1e-9);
  for (int corner = 0; corner < 8; ++corner) {
    Eigen::VectorXd h = Eigen::VectorXd::Zero(12);
    h.head<3>() << ((corner & 1) ? 1.0 : -1.0), ((corner & 2) ? 2.0 : -2.0), ((corner & 4) ? -20.0 : -30.0);
    EXPECT_TRUE(config.space.contains(frame.from_world(h))) << "corner " << corner;
  }
  Eigen::VectorXd pose = Eigen::VectorXd::Zero(12);
  pose.head<3>() << 0.5, 1.0, -25.0;
  ASSERT_TRUE(config.tracker.initial_pose);
  EXPECT_LT((*config.tracker.initial_pose - frame.from_world(pose)).norm(), 1e-9);
  EXPECT_LT((frame.to_world(*config.tracker.initial_pose) - pose).norm(), 1e-9);
}

// An oblique probe: the box about the world box's corners in the probe's
// frame is larger than the world box, and the search is kept within the
// world box itself; an initial pose outside it, or tilted past the bounds
// in the probe's frame, is refused naming why.
TEST(EngineConfig, ATurnedSensorsSearchStaysInTheWorldBox) {
  const std::string box = "[search]\nposition_min_mm = [11.0, 16.0, -3.0]\nposition_max_mm = [14.0, 22.0, 10.0]\n";
  const auto setup = gtrack::testing::probe_setup("[30, 45, 10]", box);
  const auto config = gtrack::engine_config(setup);
  const gtrack::SensorFrame frame = gtrack::sensor_frame(*setup.sensor);
  ASSERT_TRUE(config.space.position_box);
  std::mt19937_64 rng(5);
  int moved = 0;
  for (int i = 0; i < 200; ++i) {
    Eigen::VectorXd h = Eigen::VectorXd::Zero(12);
    for (int d = 0; d < 3; ++d) {
      h[d] = std::uniform_real_distribution<double>(config.space.lower[d], config.space.upper[d])(rng);
    }
    const Eigen::Vector3d before = frame.point_to_world(h.head<3>());
    config.space.clamp(h);
    const Eigen::Vector3d world = frame.point_to_world(h.head<3>());
    EXPECT_TRUE((world.array() >= Eigen::Array3d(11, 16, -3) - 1e-9).all() &&
                (world.array() <= Eigen::Array3d(14, 22, 10) + 1e-9).all())
        << world.transpose();
    EXPECT_TRUE(config.space.contains(h));
    moved += (world - before).norm() > 1e-9;
  }
  EXPECT_GT(moved, 50);  // the box about the corners holds much outside the world box
  const std::string pose = "[tracker]\ninitial_pose = [16.0, 19.0, 3.0, 0.0, 0.0, 0.0, 0, 0, 0, 0, 0, 0]\n";
  try {
    gtrack::engine_config(gtrack::testing::probe_setup("[30, 45, 10]", box + pose));
    ADD_FAILURE() << "an initial pose outside the world box was taken";
  } catch (const gtrack::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("x_mm is 16, outside [11, 14] ([search] bounds)"), std::string::npos)
        << e.what();
  }
  // A probe looking down world -z sees a gripper lying flat edge-on (rx =
  // 90 deg in its frame); tilted 10 deg more, it is past the default bounds.
  try {
    gtrack::engine_config(gtrack::testing::probe_setup(
        "[-90, 0, 0]", "[tracker]\ninitial_pose = [0.0, 0.0, -20.0, 10.0, 0.0, 0.0, 0, 0, 0, 0, 0, 0]\n"));
    ADD_FAILURE() << "a pose tilted past the bounds was taken";
  } catch (const gtrack::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rx_deg is 100, outside [-90, 90] (the angles taken in the sensor's frame"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace

namespace {

// The coarse search (first frame, after a loss, re-detection) on 20 random
// poses of the folded or flat gripper: every one is found, in the image
// plane and in its fold. (Tilt is left out: at 64 render pixels across, a
// folded gripper's tilt sign is not decided by its outline.)
TEST(Tracker, CoarseSearchFindsRandomPoses) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> xy(-1, 1), tilt(-30, 30), rz(-180, 180), q(0, 60);
  for (int i = 0; i < 20; ++i) {
    Eigen::VectorXd h(12);
    h << xy(rng), xy(rng), 100.0, tilt(rng), tilt(rng), rz(rng), 0, 0, 0, 0, 0, 0;
    h.tail(6).setConstant(q(rng));
    gtrack::Tracker tracker(setup, config);
    const auto e = tracker.process(scene(setup, h, i), i, 0.0, std::nullopt);
    EXPECT_EQ(e.status, gtrack::TrackStatus::Search);
    EXPECT_LT(e.terms.dice, 0.1) << "pose " << i;
    EXPECT_LT((e.hypothesis.head<2>() - h.head<2>()).norm(), 0.2) << "pose " << i;
    EXPECT_LT(std::abs(e.hypothesis.tail(6).mean() - h[6]), 12.0) << "pose " << i;
  }
}

// A random pose at 100 mm: (x, y) drawn from `xy`, tilted by a draw of
// `theta` towards a direction drawn from `angle` and turned about its own
// axis by another draw of `angle` (R = Rz(a) Rx(theta) Rz(tau)), every
// joint at one draw of `q`. Returns the pose and R.
std::pair<Eigen::VectorXd, Eigen::Matrix3d> draw_tilted_pose(std::mt19937_64& rng,
                                                             std::uniform_real_distribution<double>& xy,
                                                             std::uniform_real_distribution<double>& theta,
                                                             std::uniform_real_distribution<double>& angle,
                                                             std::uniform_real_distribution<double>& q) {
  const Eigen::Matrix3d R = gtrack::rotation_from_euler_deg(0, 0, angle(rng)) *
                            gtrack::rotation_from_euler_deg(theta(rng), 0, 0) *
                            gtrack::rotation_from_euler_deg(0, 0, angle(rng));
  Eigen::VectorXd h(12);
  h.head<3>() << xy(rng), xy(rng), 100.0;
  h.segment<3>(3) = gtrack::euler_deg_from_rotation(R);
  h.tail(6).setConstant(q(rng));
  return {h, R};
}

// Fingers fold one way: with the joints' lower limit at 0 (the plugins'
// default), a slightly folded, tilted gripper is found on its own tilt
// branch. Below 0, the tilt's mirror with the fold reversed, (rx, ry, q) ->
// (-rx, -ry, -q), casts the outline of the truth seen through a mirror in
// the image plane: nearly the same outline, which the search may return.
TEST(Tracker, TheFoldDecidesTheTiltSign) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> xy(-0.5, 0.5), theta(15, 30), angle(-180, 180), q(4, 10);
  int right = 0;
  for (int i = 0; i < 12; ++i) {
    const auto [h, R] = draw_tilted_pose(rng, xy, theta, angle, q);
    gtrack::Tracker tracker(setup, config);
    const auto e = tracker.process(scene(setup, h, 300 + i), i, 0.0, std::nullopt);
    const Eigen::Vector3d n = R.col(2), mirror(-n.x(), -n.y(), n.z());
    const Eigen::Vector3d found =
        gtrack::rotation_from_euler_deg(e.hypothesis[3], e.hypothesis[4], e.hypothesis[5]).col(2);
    if ((found - n).norm() < (found - mirror).norm()) {
      ++right;
    } else {
      std::printf("pose %d: tilt on the mirror branch, joints %.1f (truth %.1f)\n", i, e.hypothesis.tail(6).mean(),
                  h[6]);
    }
    EXPECT_GE(e.hypothesis.tail(6).minCoeff(), 0.0) << "pose " << i;
  }
  EXPECT_EQ(right, 12);
}

// The coarse search on strongly tilted grippers (40-50 deg, towards any
// direction of the image, turned by any angle about their own axis). The
// grid must hold every such configuration up to its refinements' spreads,
// and a grid point must be placed where its outline meets the observed one,
// not with its palm on the outline's centroid.
TEST(Tracker, CoarseSearchFindsStronglyTiltedPoses) {
  auto setup = make_setup();
  const auto config = gtrack::engine_config(setup);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> xy(-0.8, 0.8), theta(40, 50), angle(-180, 180), q(0, 60);
  int found = 0;
  for (int i = 0; i < 12; ++i) {
    const auto [h, R] = draw_tilted_pose(rng, xy, theta, angle, q);
    gtrack::Tracker tracker(setup, config);
    const auto e = tracker.process(scene(setup, h, 100 + i), i, 0.0, std::nullopt);
    const double truth = tracker.score(h).dice;
    // 62 um per render pixel: within two pixels, with an outline nearly as
    // good as the truth's.
    const double off = (e.hypothesis.head<2>() - h.head<2>()).norm();
    if (off < 0.125 && e.terms.dice < truth + 0.03) ++found;
    else std::printf("pose %d: %.3f mm off, D %.4f against the truth's %.4f\n", i, off, e.terms.dice, truth);
  }
  // One may be missed (a nearly flat gripper at 49 deg, found 84 um off).
  // Without the centring 6 are, with the former grid over the Euler angles'
  // rz 3, with neither 9.
  EXPECT_GE(found, 11);
}

// The test config with a search box of +-6 mm in x and y, so that a
// gripper may lie partly or mostly beyond the image's +-4 mm.
std::string config_with_wide_box() {
  std::string text = kConfig;
  const std::string box = "position_min_mm = [-3.0, -3.0, 98.0]\nposition_max_mm = [3.0, 3.0, 102.0]";
  text.replace(text.find(box), box.size(), "position_min_mm = [-6.0, -6.0, 98.0]\nposition_max_mm = [6.0, 6.0, 102.0]");
  return text;
}

// The coarse search on a gripper that is partly out of the image (its palm
// centre 0.2 mm inside a border, about 45 % of it outside; any tilt up to
// 30 deg, turn and fold): the observed centroid is that of the visible part,
// and a grid point is placed so that its own visible part is centred there.
TEST(Tracker, CoarseSearchFindsGrippersAtTheBorder) {
  const std::string config_text = config_with_wide_box();
  auto setup = gtrack::load_setup(gtrack::ConfigTable::parse(config_text, "<test>"), {});
  const auto config = gtrack::engine_config(setup);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> along(-2, 2), tilt(-30, 30), rz(-180, 180), q(0, 60);
  int found = 0;
  for (int i = 0; i < 12; ++i) {
    Eigen::VectorXd h(12);
    const double edge = (i % 2 == 0 ? 1 : -1) * 3.8;  // the image spans +-4 mm
    if (i % 4 < 2) h.head<3>() << edge, along(rng), 100.0;
    else h.head<3>() << along(rng), edge, 100.0;
    h.segment<3>(3) << tilt(rng), tilt(rng), rz(rng);
    h.tail(6).setConstant(q(rng));
    gtrack::Tracker tracker(setup, config);
    const auto e = tracker.process(scene(setup, h, 200 + i), i, 0.0, std::nullopt);
    const double truth = tracker.score(h).dice;
    // Judged by the outline only: with half of it out of view, places up to
    // 0.3 mm apart explain the visible part as well as the truth does.
    if (e.terms.dice < truth + 0.03) ++found;
    else std::printf("pose %d: D %.4f against the truth's %.4f\n", i, e.terms.dice, truth);
  }
  // Centred on the whole outline instead of its visible part, 6 are missed.
  EXPECT_GE(found, 11);
}

// A gripper coming into view: its palm centre 0.3-0.9 mm beyond a border,
// a sliver of it in the image. Its rotation and fold are among the coarse
// grid's (flat, turned by a multiple of the grid's 5 deg step, the joints
// on one of its four values), so only the place is to be found: the centred
// grid point shows about half of its outline, far more than O, and the
// grid's points moved out across the border find it.
TEST(Tracker, CoarseSearchFindsGrippersComingIntoView) {
  const std::string config_text = config_with_wide_box();
  const auto count_found = [&](int steps) {
    auto setup = gtrack::load_setup(
        gtrack::ConfigTable::parse(config_text + "\n[tracker]\ncoarse_border_steps = " + std::to_string(steps) + "\n",
                                   "<test>"),
        {});
    const auto config = gtrack::engine_config(setup);
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> along(-2, 2), beyond(0.3, 0.9);
    std::uniform_int_distribution<int> turn(0, 71), fold(0, 3);
    int found = 0;
    for (int i = 0; i < 12; ++i) {
      Eigen::VectorXd h(12);
      const double edge = (i % 2 == 0 ? 1 : -1) * (4.0 + beyond(rng));  // the image spans +-4 mm
      if (i % 4 < 2) h.head<3>() << edge, along(rng), 100.0;
      else h.head<3>() << along(rng), edge, 100.0;
      h.segment<3>(3) << 0.0, 0.0, 5.0 * turn(rng) - 180.0;
      h.tail(6).setConstant(20.0 * fold(rng));
      gtrack::Tracker tracker(setup, config);
      const auto e = tracker.process(scene(setup, h, 400 + i), i, 0.0, std::nullopt);
      const double truth = tracker.score(h).dice;
      if (e.terms.dice < truth + 0.03) ++found;
      else std::printf("%d steps, pose %d: D %.4f against the truth's %.4f\n", steps, i, e.terms.dice, truth);
    }
    return found;
  };
  const int with_steps = count_found(3), without = count_found(0);
  std::printf("found %d of 12 with the border steps, %d without\n", with_steps, without);
  // 7 and 1. The steps are 0.3 model radii (0.6 mm, 10 render pixels
  // here): on a sliver a few pixels deep, a grid point of the truth's
  // rotation left up to half a step from its place misfits it, a grid point
  // of another rotation can rank above it, and the refinements do not
  // always recover. Steps of 0.15 radii find all 12 here, but tracked the
  // hydrogel sequences no better (docs/tracker.md).
  EXPECT_GE(with_steps, 6);
  EXPECT_GE(with_steps, without + 4);
  for (const char* bad : {"-1", "9", "1.5"}) {
    const std::string m = engine_config_error(std::string("[tracker]\ncoarse_border_steps = ") + bad + "\n");
    EXPECT_NE(m.find("coarse_border_steps"), std::string::npos) << m;
  }
}

}  // namespace
