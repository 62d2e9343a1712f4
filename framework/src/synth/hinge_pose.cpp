#include "synth/hinge_pose.hpp"

#include <cmath>
#include <numbers>

namespace gtrack::synth {

void pose_hinges(const ArticulatedModel& model, const Eigen::VectorXd& h, const std::vector<double>& hinge_deg,
                 std::vector<Eigen::Vector3d>& out) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  const auto& G = model.geometry();
  const int L = model.max_links();
  // Per finger and link: hinge point (radial, z) and the link's direction.
  std::vector<Eigen::Vector4d> links(G.fingers.size() * L);
  for (size_t f = 0; f < G.fingers.size(); ++f) {
    double hr = 0, hz = 0, theta = 0;
    for (size_t j = 0; j < G.fingers[f].links.size(); ++j) {
      theta += hinge_deg[f * L + j] * kDeg;
      links[f * L + j] = {hr, hz, std::cos(theta), std::sin(theta)};
      hr += G.fingers[f].links[j].length_mm * std::cos(theta);
      hz += G.fingers[f].links[j].length_mm * std::sin(theta);
    }
  }
  const Eigen::Matrix3d R = rotation_from_euler_deg(h[3], h[4], h[5]);
  const Eigen::Vector3d t = h.head<3>();
  const auto& mesh = model.mesh();
  out.resize(mesh.size());
  for (size_t i = 0; i < mesh.size(); ++i) {
    const ModelVertex& v = mesh[i];
    Eigen::Vector3d p(v.a, v.b, 0);
    if (v.finger >= 0) {
      const FingerShape& F = G.fingers[v.finger];
      const Eigen::Vector4d& k = links[v.finger * L + v.link];
      const double phi = F.direction_deg * kDeg;
      const Eigen::Vector2d d(std::cos(phi), std::sin(phi)), l(-std::sin(phi), std::cos(phi));
      const double r = k[0] + v.a * k[2], z = k[1] + v.a * k[3];
      const Eigen::Vector2d q = F.base_mm + r * d + double(v.b) * l;
      p = Eigen::Vector3d(q.x(), q.y(), z);
    }
    out[i] = R * p + t;
  }
}

std::vector<double> shared_hinges(const ArticulatedModel& model, const Eigen::VectorXd& h) {
  const int L = model.max_links();
  std::vector<double> out(model.fingers() * L, 0.0);
  for (int f = 0; f < model.fingers(); ++f) {
    for (int j = 0; j < L; ++j) out[f * L + j] = h[kPoseDims + f];
  }
  return out;
}

}  // namespace gtrack::synth
