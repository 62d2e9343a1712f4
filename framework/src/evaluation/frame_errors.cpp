// One estimate against one truth, modulo the gripper's rotational symmetry.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "gtrack/evaluation.hpp"

namespace gtrack {

namespace {

// The mean distance between corresponding endpoints; with `across` (unit
// length), of their differences less their components along it.
double mean_endpoint_distance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                              const Eigen::Vector3d* across = nullptr) {
  double sum = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const Eigen::Vector3d d = a[i] - b[i];
    sum += across ? (d - d.dot(*across) * *across).norm() : d.norm();
  }
  return a.empty() ? 0.0 : sum / a.size();
}

// The estimate's palm normal is on the other branch of a tilted truth's
// tilt sign (FrameErrors::tilt_branch).
bool on_other_tilt_branch(const Eigen::VectorXd& truth, const Eigen::VectorXd& estimate,
                          const Eigen::Vector3d& line_of_sight) {
  if (line_of_sight.norm() == 0) return false;
  const Eigen::Vector3d v = line_of_sight.normalized();
  const Eigen::Vector3d n = rotation_from_euler_deg(truth[3], truth[4], truth[5]).col(2);
  const Eigen::Vector3d m = 2 * n.dot(v) * v - n;
  const Eigen::Vector3d e = rotation_from_euler_deg(estimate[3], estimate[4], estimate[5]).col(2);
  const double tilt_deg = std::acos(std::clamp(std::abs(n.dot(v)), 0.0, 1.0)) * 180.0 / std::numbers::pi;
  // Nearer the mirror than the truth, and not upside down (e near -n).
  return tilt_deg > FrameErrors::kMirrorMinTiltDeg && e.dot(m) > std::abs(e.dot(n));
}

// Every link of the configuration lies within kFlatShare of the model's
// radius of the palm plane.
bool is_flat(const ArticulatedModel& model, const Eigen::VectorXd& h) {
  Eigen::VectorXd shape = h;
  shape.head<kPoseDims>().setZero();  // the model frame: the palm in its XY plane
  double lo = 0, hi = 0;
  for (const Eigen::Vector3d& p : model.link_endpoints(shape)) {
    lo = std::min(lo, p.z());
    hi = std::max(hi, p.z());
  }
  return hi - lo <= FrameErrors::kFlatShare * model.radius_mm();
}

}  // namespace

double geodesic_angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Matrix3d r = rotation_from_euler_deg(a.x(), a.y(), a.z()).transpose() *
                            rotation_from_euler_deg(b.x(), b.y(), b.z());
  // acos is ill-conditioned near 0; the angle-axis route is not.
  return Eigen::AngleAxisd(r).angle() * 180.0 / std::numbers::pi;
}

Eigen::Vector3d line_of_sight(const Projection& projection, const Eigen::Vector3d& world_mm) {
  // The pixel's line of sight is {X : (p1 - u p3).[X;1] = 0, (p2 - v p3).[X;1] = 0};
  // its direction is the cross product of the two planes' normals.
  const Eigen::Matrix<double, 3, 4>& p = projection.world_to_image;
  const Eigen::Vector3d x = p * world_mm.homogeneous();
  if (x.z() == 0) return Eigen::Vector3d::UnitZ();
  const double u = x.x() / x.z(), v = x.y() / x.z();
  const Eigen::Vector3d a = (p.row(0) - u * p.row(2)).head<3>().transpose();
  const Eigen::Vector3d b = (p.row(1) - v * p.row(2)).head<3>().transpose();
  const Eigen::Vector3d d = a.cross(b);
  return d.norm() > 0 ? Eigen::Vector3d(d.normalized()) : Eigen::Vector3d::UnitZ();
}

FrameErrors compare_to_truth(const ArticulatedModel& model, const Eigen::VectorXd& truth,
                             const Eigen::VectorXd& estimate, const Eigen::Vector3d& line_of_sight,
                             const Eigen::Vector3d& viewing_axis) {
  const auto truth_ends = model.link_endpoints(truth);
  const int order = std::max(1, model.geometry().symmetry_order);
  FrameErrors best;
  double best_end = 0;
  for (int k = 0; k < order; ++k) {
    const Eigen::VectorXd e = model.symmetric_equivalent(estimate, k);
    const auto ends = model.link_endpoints(e);
    const double end = mean_endpoint_distance(ends, truth_ends);
    // The first equivalent is always taken, so that an error that is not
    // finite is reported as such, never as the default of 0.
    if (k > 0 && !(end < best_end)) continue;
    best_end = end;
    FrameErrors f;
    f.symmetry_k = k;
    f.endpoint_um = 1000 * end;
    f.endpoint_inplane_um = 1000 * mean_endpoint_distance(ends, truth_ends, &viewing_axis);
    const Eigen::Vector3d d = e.head<3>() - truth.head<3>();
    f.position_um = 1000 * d.norm();
    const double along = d.dot(viewing_axis);
    f.inplane_um = 1000 * (d - along * viewing_axis).norm();
    f.depth_um = 1000 * std::abs(along);
    // The rotation taking the truth to the estimate (angle-axis: acos is
    // ill-conditioned near 0), split about the frame's own axes: unlike
    // Euler differences, its parts stay small near ry = +-90 deg, where rx
    // and rz trade off freely.
    const Eigen::AngleAxisd turn(rotation_from_euler_deg(e[3], e[4], e[5]) *
                                 rotation_from_euler_deg(truth[3], truth[4], truth[5]).transpose());
    f.orientation_deg = turn.angle() * 180.0 / std::numbers::pi;
    f.axis_deg = (f.orientation_deg * turn.axis()).cwiseAbs();
    const int F = model.fingers();
    double joints = 0;
    for (int j = 0; j < F; ++j) joints += std::abs(e[kPoseDims + j] - truth[kPoseDims + j]);
    f.joint_deg = F ? joints / F : 0;
    best = f;
  }
  best.tilt_branch = on_other_tilt_branch(truth, estimate, line_of_sight);
  best.tilt_mirror = best.tilt_branch && is_flat(model, truth);
  return best;
}

}  // namespace gtrack
