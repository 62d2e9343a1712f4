// Synthesise a short sequence, track it through the library API, evaluate:
// the thresholds fail when tracking breaks, not when it is a little worse.
#include <gtest/gtest.h>

#include <filesystem>

#include "gtrack/engine_config.hpp"
#include "gtrack/synth.hpp"
#include "gtrack/synthetic_benchmark.hpp"

namespace fs = std::filesystem;

TEST(EndToEnd, SyntheticMicroscopeSequenceIsTracked) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_end_to_end_test";
  fs::remove_all(dir);
  const gtrack::Setup source =
      gtrack::load_setup(fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" / "microscope_hydrogel.toml", {});
  gtrack::SynthOptions o;
  o.frames = 24;
  o.seed = 5;
  const auto synth = gtrack::write_synthetic_sequence(source, o, dir);
  ASSERT_EQ(synth.frames, 24);

  const gtrack::Setup setup = gtrack::load_synthetic_setup(dir);
  gtrack::EngineConfig cfg = gtrack::engine_config(setup);
  gtrack::check_root_keys(setup);
  cfg.render.backend = "cpu";  // the same numbers on every machine
  cfg.tracker.overlay = false;
  const auto run = gtrack::run_synthetic_benchmark(setup, cfg, dir);
  const auto& ev = run.evaluation;
  std::printf("in-plane %.1f um, depth %.1f um, orientation %.2f deg, joints %.2f deg, endpoints %.1f um, "
              "%d lost, %.1f frames/s\n",
              ev.in_view.position_inplane_um.mean, ev.in_view.depth_um.mean, ev.in_view.orientation_deg.mean,
              ev.in_view.joint_deg.mean, ev.in_view.endpoint_um.mean, ev.lost_frames, run.tracker_fps);
  EXPECT_EQ(ev.frames, 24);
  EXPECT_EQ(ev.lost_in_view_frames, 0);
  // A lost track is off by hundreds of micrometres in the image plane. The
  // angular bounds are loose on purpose: today's tracker confuses the tilt of
  // a nearly flat gripper with its mirror image (a near-orthographic
  // silhouette cannot tell them apart) and is far from the paper's 1.7 deg
  // and 1.4 deg on this data; docs/RESULTS.md has the figures.
  EXPECT_LT(ev.in_view.position_inplane_um.mean, 60.0);
  EXPECT_LT(ev.in_view.joint_deg.mean, 15.0);
  EXPECT_LT(ev.in_view.orientation_deg.mean, 45.0);
  fs::remove_all(dir);
}
