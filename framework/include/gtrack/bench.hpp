// Throughput measurement, shared by `gtrack bench` and the benchmark target.
//
// One scene (a gripper seen by a pinhole camera, rendered at a square render
// size with the gripper about `gripper_px` across, the observation being the
// gripper at a nominal pose) and random hypotheses near that pose, so that
// every backend and the OpenCV baseline are timed on identical work. Times
// are wall-clock over whole batches or frames, warm-up excluded; nothing
// here decides whether a number is good.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/model.hpp"
#include "gtrack/renderer.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack {

struct BenchScene {
  ArticulatedModel model;
  Projection projection;  // full-resolution camera
  double scale = 0.25;    // render size = scale * image size
  Eigen::VectorXd nominal;
  cv::Mat observation;   // CV_8U at render size: the gripper at `nominal`
  cv::Mat rim;           // the one-pixel ring just outside it, counted as the tracker's rim
  double gripper_px = 0;  // tip-to-tip extent of the open gripper at render size
};

// The hydrogel gripper from its plugin if it can be loaded from the default
// search path plus `plugin_paths`, else the same shape built in code.
// `source` says which one was used (and why the plugin was not).
GTRACK_API ArticulatedModel load_bench_gripper(const std::vector<std::filesystem::path>& plugin_paths,
                                               std::string& source);

GTRACK_API BenchScene make_bench_scene(const ArticulatedModel& model, int render_side = 256,
                                       double gripper_px = 114);

// `count` hypotheses near the nominal pose (one per column): a few tenths of
// a millimetre, up to 25 deg of tilt, any turn about the axis, any fold.
GTRACK_API Eigen::MatrixXd bench_hypotheses(const BenchScene& scene, int count, std::uint64_t seed);

struct ThroughputResult {
  std::string backend;
  double per_second = 0;   // hypotheses or frames, see the function
  std::uint64_t count = 0;  // hypotheses or frames done in the timed part
  double seconds = 0;
};

// Hypotheses per second: batches of `batch` distinct hypotheses evaluated
// one after the other for at least `seconds`.
GTRACK_API ThroughputResult measure_hypotheses(Renderer& renderer, const BenchScene& scene, double seconds,
                                               int batch = 32);

// Frames per second of a whole tracking frame's search: the paper's PSO
// (N = 32, G = 25 by default) from a swarm initialised around the nominal
// pose, with the cost of eq. (1) (no stimulus), for at least `seconds`.
// Segmentation and I/O are not included.
GTRACK_API ThroughputResult measure_pso_frames(Renderer& renderer, const BenchScene& scene, double seconds,
                                               int particles = 32, int generations = 25);

// The comparison point: the same evaluation written the way an OpenCV user
// would (cv::fillConvexPoly per projected triangle into a byte mask, then
// cv::bitwise_and / cv::bitwise_or and cv::countNonZero over the image).
// It follows the Renderer contract but fills edge pixels more generously
// (about 3% more pixels), so it is a speed reference, not an oracle.
GTRACK_API std::unique_ptr<Renderer> make_opencv_baseline(const RenderOptions& options);

}  // namespace gtrack
