// Grid of hypotheses at the observation's centroid, then a PSO per candidate.
#include "coarse_search.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <numbers>
#include <numeric>
#include <opencv2/imgproc.hpp>

namespace gtrack::detail {

Eigen::Vector3d lift_pixel(const Projection& p, double u, double v, const Eigen::Vector3d& near) {
  // The pixel's line of sight is {X : (p1 - u p3).[X;1] = 0, (p2 - v p3).[X;1] = 0};
  // the minimum-norm correction from `near` onto it solves the 2x3 system.
  const Eigen::Matrix<double, 3, 4>& m = p.world_to_image;
  Eigen::Matrix<double, 2, 4> rows;
  rows.row(0) = m.row(0) - u * m.row(2);
  rows.row(1) = m.row(1) - v * m.row(2);
  const Eigen::Matrix<double, 2, 3> a = rows.leftCols<3>();
  const Eigen::Vector2d r = -(a * near + rows.col(3));
  const Eigen::Matrix2d aat = a * a.transpose();
  if (std::abs(aat.determinant()) < 1e-18) return near;
  return near + a.transpose() * aat.ldlt().solve(r);
}

CoarseSearchResult coarse_search(const CoarseSearchInput& in, const EngineConfig& config, CostEvaluator& cost,
                                 std::mt19937_64& rng) {
  const ParameterSpace& space = config.space;
  const ArticulatedModel& model = *in.model;
  const int dims = space.dims();
  const cv::Moments mo = cv::moments(*in.observation, true);
  const double u = mo.m00 > 0 ? mo.m10 / mo.m00 + 0.5 : in.observation->cols * 0.5;
  const double v = mo.m00 > 0 ? mo.m01 / mo.m00 + 0.5 : in.observation->rows * 0.5;
  const Eigen::Vector3d centre = lift_pixel(in.render_projection, u, v, in.nominal_mm);

  const TrackerConfig& tc = config.tracker;
  const double period = 360.0 / std::max(1, model.geometry().symmetry_order);
  const int rz_steps = tc.coarse_rz_steps;
  const double tilt = 25.0;
  // Flat, then two rings of tilts: 25 deg about x or y, and 50 deg about x,
  // y and the diagonals (strongly tilted, folded grippers have compact
  // outlines that the first ring does not reach).
  std::vector<std::pair<double, double>> tilts = {{0, 0}, {tilt, 0}, {-tilt, 0}, {0, tilt}, {0, -tilt}};
  if (tc.coarse_wide_tilts) {
    const double wide = 2 * tilt, diag = wide / std::numbers::sqrt2;
    for (const auto& t : std::vector<std::pair<double, double>>{
             {wide, 0}, {-wide, 0}, {0, wide}, {0, -wide}, {diag, diag}, {diag, -diag}, {-diag, diag}, {-diag, -diag}}) {
      tilts.push_back(t);
    }
  }
  std::vector<double> joints;
  for (int j = 0; j < 4; ++j) joints.push_back(in.joint_lo + (in.joint_hi - in.joint_lo) * j / 3.0);

  Eigen::MatrixXd grid(dims, rz_steps * static_cast<int>(tilts.size() * joints.size()));
  int col = 0;
  for (int r = 0; r < rz_steps; ++r) {
    for (const auto& [rx, ry] : tilts) {
      for (double q : joints) {
        Eigen::VectorXd h(dims);
        h.head<3>() = centre;
        h[3] = rx;
        h[4] = ry;
        h[5] = period * r / rz_steps;
        h.tail(dims - kPoseDims).setConstant(q);
        space.clamp(h);
        grid.col(col++) = h;
      }
    }
  }
  CoarseSearchResult result;
  Eigen::VectorXd scores;
  cost.evaluate(grid, scores);
  result.evaluations += static_cast<std::uint64_t>(grid.cols());

  std::vector<int> order(static_cast<size_t>(grid.cols()));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return scores[a] < scores[b]; });

  // Wide spreads: the centroid of a partly hidden gripper is off by a fraction
  // of its size, and the grid's steps bound the angular error.
  const double radius = model.radius_mm();
  Eigen::VectorXd spread(dims);
  spread << 0.3 * radius, 0.3 * radius, tc.init_spread[2], tilt, tilt, 0.75 * period / rz_steps,
      Eigen::VectorXd::Constant(dims - kPoseDims, std::max(5.0, (in.joint_hi - in.joint_lo) / 3.0));
  ParticleSwarm pso(config.pso, space);
  pso.set_randomization_spread(spread);
  result.cost = std::numeric_limits<double>::infinity();
  const int candidates = std::min<int>(tc.coarse_candidates, static_cast<int>(order.size()));
  const BatchObjective objective = [&](const Eigen::MatrixXd& x, Eigen::VectorXd& c) { cost.evaluate(x, c); };
  for (int c = 0; c < candidates; ++c) {
    const Eigen::VectorXd start = grid.col(order[static_cast<size_t>(c)]);
    const Eigen::MatrixXd init = biased_initial_swarm(start, spread, 0.5, config.pso.particles, space, rng);
    const PsoResult r = pso.run(init, objective, rng);
    result.evaluations += r.evaluations;
    if (r.best_cost < result.cost) {
      result.cost = r.best_cost;
      result.best = r.best;
    }
  }
  return result;
}

}  // namespace gtrack::detail
