// Of a configuration's symmetric equivalents, the one nearest another's.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack::detail {

// Of h's symmetric equivalents (the same silhouette), the one whose angles
// are nearest `to`'s, so that the temporal term compares like with like.
// The angles are compared in `frame`, the sensor's (the tracker's; for a
// sensor turned in the world, the world's angles can be near gimbal lock
// where the sensor's are not).
inline Eigen::VectorXd nearest_equivalent(const ArticulatedModel& model, const Eigen::VectorXd& h,
                                          const Eigen::VectorXd& to, const SensorFrame& frame = {}) {
  Eigen::VectorXd best = h;
  double nearest = std::numeric_limits<double>::infinity();
  const Eigen::VectorXd to_in_frame = frame.from_world(to);
  for (int k = 0; k < std::max(1, model.geometry().symmetry_order); ++k) {
    const Eigen::VectorXd e = model.symmetric_equivalent(h, k);
    const Eigen::VectorXd e_in_frame = frame.from_world(e);
    double d = 0;
    for (int a = 3; a < kPoseDims; ++a) d += std::pow(std::remainder(e_in_frame[a] - to_in_frame[a], 360.0), 2);
    if (d < nearest) {
      nearest = d;
      best = e;
    }
  }
  return best;
}

}  // namespace gtrack::detail
