// Synthesise a short sequence of every setup (paper Sections 5.1-5.3), track
// it through the library API and evaluate: the thresholds fail when tracking
// breaks (a lost or drifting track), not when it is a little worse.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "gtrack/engine_config.hpp"
#include "gtrack/synth.hpp"
#include "gtrack/synthetic_benchmark.hpp"

namespace fs = std::filesystem;

namespace {

struct SetupCase {
  const char* name;    // test name
  const char* config;  // in configs/
  const char* preset;  // gtrack synth preset
  int frames;
  std::uint64_t seed;
  // Upper bounds on the means over in-view frames.
  double inplane_um, orientation_deg, joint_deg;
};

void PrintTo(const SetupCase& c, std::ostream* os) { *os << c.name; }

class EndToEnd : public ::testing::TestWithParam<SetupCase> {};

TEST_P(EndToEnd, SyntheticSequenceIsTracked) {
  const SetupCase& c = GetParam();
  const fs::path dir = fs::temp_directory_path() / (std::string("gtrack_end_to_end_") + c.name);
  fs::remove_all(dir);
  const gtrack::Setup source = gtrack::load_setup(fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" / c.config, {});
  gtrack::SynthOptions o;
  o.frames = c.frames;
  o.seed = c.seed;
  o.preset = c.preset;
  const auto synth = gtrack::write_synthetic_sequence(source, o, dir);
  ASSERT_EQ(synth.frames, c.frames);

  const gtrack::Setup setup = gtrack::load_synthetic_setup(dir);
  gtrack::EngineConfig cfg = gtrack::engine_config(setup);
  gtrack::check_root_keys(setup);
  cfg.render.backend = "cpu";  // the same numbers on every machine
  cfg.tracker.overlay = false;
  const auto run = gtrack::run_synthetic_benchmark(setup, cfg, dir);
  const auto& ev = run.evaluation;
  std::printf("%s: in-plane %.1f um, depth %.1f um, orientation %.2f deg, joints %.2f deg, endpoints %.1f um, "
              "%d lost, %.1f frames/s\n",
              c.name, ev.in_view.position_inplane_um.mean, ev.in_view.depth_um.mean, ev.in_view.orientation_deg.mean,
              ev.in_view.joint_deg.mean, ev.in_view.endpoint_um.mean, ev.lost_frames, run.tracker_fps);
  EXPECT_EQ(ev.frames, c.frames);
  EXPECT_EQ(ev.lost_in_view_frames, 0);
  // A lost track is off by several gripper radii in the image plane. The
  // angular bounds are loose on purpose: the tracker confuses the tilt of a
  // nearly flat gripper with its mirror image (a near-orthographic silhouette
  // cannot tell them apart) and is far from the paper's 1.7 deg and 1.4 deg;
  // docs/RESULTS.md has the figures.
  EXPECT_LT(ev.in_view.position_inplane_um.mean, c.inplane_um);
  EXPECT_LT(ev.in_view.orientation_deg.mean, c.orientation_deg);
  EXPECT_LT(ev.in_view.joint_deg.mean, c.joint_deg);
  fs::remove_all(dir);
}

// One per setup of the paper; the configs are the shipped ones. Measured on
// these sequences (in-plane): 6.4, 1.3, 1.2 and 17.3 um. A lost track is off
// by a gripper radius or more (2000, 450, 375 and 2000 um): the bounds sit
// between, scaled to each setup's pixel size; the ultrasound one is the
// paper's 2 pixels (180 um).
INSTANTIATE_TEST_SUITE_P(
    EverySetup, EndToEnd,
    ::testing::Values(SetupCase{"microscope_hydrogel", "microscope_hydrogel.toml", "microscope", 24, 5, 60, 45, 15},
                      SetupCase{"microscope_metallic_six", "microscope_metallic_six.toml", "metallic_six", 24, 5, 20,
                                45, 15},
                      SetupCase{"microscope_metallic_two", "microscope_metallic_two.toml", "metallic_two", 24, 5, 20,
                                45, 15},
                      SetupCase{"ultrasound_hydrogel", "ultrasound_hydrogel.toml", "ultrasound", 24, 5, 180, 45, 15}),
    [](const ::testing::TestParamInfo<SetupCase>& i) { return std::string(i.param.name); });

}  // namespace
