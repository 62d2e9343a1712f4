// Of a configuration's symmetric equivalents, the one nearest another's.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <limits>

#include "gtrack/evaluation.hpp"
#include "gtrack/model.hpp"

namespace gtrack::detail {

// Of h's symmetric equivalents (the same silhouette), the one whose
// orientation is nearest `to`'s, so that the temporal term and the
// two-pass fits compare like with like. Nearest is the angle of the
// rotation between the two orientations, which no frame changes: Euler
// angles' differences would not do near a 90 deg tilt about y, where rx
// and rz trade off (two orientations 1 deg apart can differ by 60 deg in
// each).
inline Eigen::VectorXd nearest_equivalent(const ArticulatedModel& model, const Eigen::VectorXd& h,
                                          const Eigen::VectorXd& to) {
  Eigen::VectorXd best = h;
  double nearest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < std::max(1, model.geometry().symmetry_order); ++k) {
    const Eigen::VectorXd e = model.symmetric_equivalent(h, k);
    const double d = geodesic_angle_deg(e.segment<3>(3), to.segment<3>(3));
    if (d < nearest) {
      nearest = d;
      best = e;
    }
  }
  return best;
}

}  // namespace gtrack::detail
