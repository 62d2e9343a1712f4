// One estimate against one truth, modulo the gripper's rotational symmetry.
#include <cmath>
#include <numbers>

#include "gtrack/evaluation.hpp"

namespace gtrack {

namespace {

double wrap_deg(double a) { return std::abs(std::remainder(a, 360.0)); }

double mean_endpoint_distance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double sum = 0;
  for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]).norm();
  return a.empty() ? 0.0 : sum / a.size();
}

}  // namespace

double geodesic_angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Matrix3d r = rotation_from_euler_deg(a.x(), a.y(), a.z()).transpose() *
                            rotation_from_euler_deg(b.x(), b.y(), b.z());
  // acos is ill-conditioned near 0; the angle-axis route is not.
  return Eigen::AngleAxisd(r).angle() * 180.0 / std::numbers::pi;
}

FrameErrors compare_to_truth(const ArticulatedModel& model, const Eigen::VectorXd& truth,
                             const Eigen::VectorXd& estimate) {
  const auto truth_ends = model.link_endpoints(truth);
  const int order = std::max(1, model.geometry().symmetry_order);
  FrameErrors best;
  double best_end = 1e300;
  for (int k = 0; k < order; ++k) {
    Eigen::VectorXd e = model.symmetric_equivalent(estimate, k);
    // One Euler branch for both sides, so that per-axis differences mean something.
    e.segment<3>(3) = euler_deg_from_rotation(rotation_from_euler_deg(e[3], e[4], e[5]));
    const double end = mean_endpoint_distance(model.link_endpoints(e), truth_ends);
    if (end >= best_end) continue;
    best_end = end;
    FrameErrors f;
    f.symmetry_k = k;
    f.endpoint_um = 1000 * end;
    const Eigen::Vector3d d = e.head<3>() - truth.head<3>();
    f.position_um = 1000 * d.norm();
    f.inplane_um = 1000 * d.head<2>().norm();
    f.depth_um = 1000 * std::abs(d.z());
    const Eigen::Vector3d te = euler_deg_from_rotation(rotation_from_euler_deg(truth[3], truth[4], truth[5]));
    f.orientation_deg = geodesic_angle_deg(te, e.segment<3>(3));
    for (int a = 0; a < 3; ++a) f.axis_deg[a] = wrap_deg(e[3 + a] - te[a]);
    const int F = model.fingers();
    double joints = 0;
    for (int j = 0; j < F; ++j) joints += std::abs(e[kPoseDims + j] - truth[kPoseDims + j]);
    f.joint_deg = F ? joints / F : 0;
    best = f;
  }
  return best;
}

}  // namespace gtrack
