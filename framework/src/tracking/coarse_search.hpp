// The search for the first frame, after a loss, and for re-detection: where
// is the gripper, roughly?
//
// The observation's centroid is lifted to 3D at the sensor's nominal depth
// (the point of the centroid's line of sight nearest the nominal position);
// a grid of hypotheses there — rz over one symmetry period, five tilts (13
// with [tracker] coarse_wide_tilts), four joint values within what the
// stimulus allows — is scored in batches, each point also tried with its
// visible outline centred on O's and, where O touches the image's border,
// moved out across it ([tracker] coarse_border_steps); the best few seed
// one PSO each with wide spreads. The best result wins.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <random>

#include "gtrack/cost.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/model.hpp"
#include "gtrack/pso.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack::detail {

struct CoarseSearchInput {
  const cv::Mat* observation = nullptr;  // render-size mask, non-empty
  Projection render_projection;          // projection at render size
  Eigen::Vector3d nominal_mm;            // sensor's nominal position
  const ArticulatedModel* model = nullptr;
  double joint_lo = 0, joint_hi = 60;    // joint values worth trying
};

struct CoarseSearchResult {
  Eigen::VectorXd best;
  double cost = 0;
  std::uint64_t evaluations = 0;
};

// Lifts render pixel (u, v) (continuous coordinates, centres at +0.5) to the
// world point on its line of sight nearest `near`.
Eigen::Vector3d lift_pixel(const Projection& p, double u, double v, const Eigen::Vector3d& near);

CoarseSearchResult coarse_search(const CoarseSearchInput& in, const EngineConfig& config, CostEvaluator& cost,
                                 std::mt19937_64& rng);

}  // namespace gtrack::detail
