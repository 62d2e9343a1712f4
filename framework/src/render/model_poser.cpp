// ModelPoser: the model.hpp formula with per-vertex constants hoisted out.
#include "render/model_poser.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "gtrack/error.hpp"

namespace gtrack::render {

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr int kMaxSlots = 256;  // links over all fingers; checked in the constructor
}  // namespace

ModelPoser::ModelPoser(const ArticulatedModel& model) : dims_(model.dims()) {
  const GripperGeometry& g = model.geometry();
  for (const FingerShape& f : g.fingers) {
    Finger F;
    F.first_slot = slots_;
    for (const LinkShape& l : f.links) F.lengths.push_back(l.length_mm);
    slots_ += static_cast<int>(f.links.size());
    fingers_.push_back(std::move(F));
  }
  if (slots_ > kMaxSlots) throw Error("gripper '" + g.name + "' has more than " + std::to_string(kMaxSlots) + " links in all; the cpu backend supports up to that");
  for (const ModelVertex& m : model.mesh()) {
    Vertex v{static_cast<double>(m.a), static_cast<double>(m.b), {0, 0}, {1, 0}, {0, 1}, -1};
    if (m.finger >= 0) {
      const FingerShape& f = g.fingers[m.finger];
      const double phi = f.direction_deg * kDeg;
      v.base = f.base_mm;
      v.dir = Eigen::Vector2d(std::cos(phi), std::sin(phi));
      v.lateral = Eigen::Vector2d(-std::sin(phi), std::cos(phi));
      v.link_slot = fingers_[m.finger].first_slot + m.link;
    }
    vertices_.push_back(v);
  }
}

void ModelPoser::pose_model(const double* h, std::vector<Eigen::Vector3d>& out) const {
  // Hinge point (r, z) and direction (cos, sin) of every link.
  double hr[kMaxSlots], hz[kMaxSlots], c[kMaxSlots], s[kMaxSlots];
  for (size_t f = 0; f < fingers_.size(); ++f) {
    const Finger& F = fingers_[f];
    const double q = h[kPoseDims + f] * kDeg;
    // Link j is tilted by (j + 1) q: its direction is the previous one turned by q.
    const double cq = std::cos(q), sq = std::sin(q);
    double r = 0, z = 0, cj = 1, sj = 0;
    for (size_t j = 0; j < F.lengths.size(); ++j) {
      const int k = F.first_slot + static_cast<int>(j);
      const double cn = cj * cq - sj * sq, sn = sj * cq + cj * sq;
      cj = cn;
      sj = sn;
      c[k] = cj;
      s[k] = sj;
      hr[k] = r;
      hz[k] = z;
      r += F.lengths[j] * cj;
      z += F.lengths[j] * sj;
    }
  }
  out.resize(vertices_.size());
  for (size_t i = 0; i < vertices_.size(); ++i) {
    const Vertex& v = vertices_[i];
    if (v.link_slot < 0) {
      out[i] = Eigen::Vector3d(v.a, v.b, 0);
      continue;
    }
    const int k = v.link_slot;
    const double r = hr[k] + v.a * c[k];
    const Eigen::Vector2d p = v.base + r * v.dir + v.b * v.lateral;
    out[i] = Eigen::Vector3d(p.x(), p.y(), hz[k] + v.a * s[k]);
  }
}

void ModelPoser::to_model_frame(const double* h, const Projection& world, Projection& out) {
  const Eigen::Matrix3d R = rotation_from_euler_deg(h[3], h[4], h[5]);
  const Eigen::Vector3d t(h[0], h[1], h[2]);
  // image = M (R x + t): the linear part becomes M R, the offset M t + m.
  out.world_to_image.leftCols<3>() = world.world_to_image.leftCols<3>() * R;
  out.world_to_image.col(3) = world.world_to_image.leftCols<3>() * t + world.world_to_image.col(3);
  out.size = world.size;
  out.clip_planes.resize(world.clip_planes.size());
  // n . (R x + t) + d = (R^T n) . x + (n . t + d).
  for (size_t i = 0; i < world.clip_planes.size(); ++i) {
    const Eigen::Vector4d& p = world.clip_planes[i];
    out.clip_planes[i] << R.transpose() * p.head<3>(), p.head<3>().dot(t) + p.w();
  }
}

}  // namespace gtrack::render
