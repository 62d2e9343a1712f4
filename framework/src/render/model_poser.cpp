// ModelPoser: per-link frames mapped to the image once per hypothesis.
#include "render/model_poser.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "gtrack/error.hpp"

namespace gtrack::render {

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr int kMaxSlots = ArticulatedModel::kMaxLinks + 1;  // palm + links over all fingers
constexpr int kRows = 3 + kMaxSensorPlanes;

}  // namespace

ModelPoser::ModelPoser(const ArticulatedModel& model) : dims_(model.dims()) {
  const GripperGeometry& g = model.geometry();
  slot_finger_.push_back(-1);
  for (size_t f = 0; f < g.fingers.size(); ++f) {
    const FingerShape& shape = g.fingers[f];
    const double phi = shape.direction_deg * kDeg;
    Finger F{shape.base_mm, {std::cos(phi), std::sin(phi)}, {-std::sin(phi), std::cos(phi)},
             static_cast<int>(slot_finger_.size()), {}};
    for (const LinkShape& l : shape.links) {
      F.lengths.push_back(l.length_mm);
      slot_finger_.push_back(static_cast<int>(f));
    }
    fingers_.push_back(std::move(F));
  }
  // ArticulatedModel refuses more links than there are slots.
  if (slot_finger_.size() > kMaxSlots) throw Error("gripper '" + g.name + "': too many links for the cpu backend");
  for (const ModelVertex& m : model.mesh()) {
    const int slot = m.finger < 0 ? 0 : fingers_[m.finger].first_slot + m.link;
    vertices_.push_back({static_cast<double>(m.a), static_cast<double>(m.b), slot});
  }
}

void ModelPoser::links(const double* h, Links* out) const {
  out[0] = {0, 0, 1, 0};
  for (size_t f = 0; f < fingers_.size(); ++f) {
    const Finger& F = fingers_[f];
    const double q = h[kPoseDims + f] * kDeg;
    // Link j is tilted by (j + 1) q: its direction is the previous one turned by q.
    const double cq = std::cos(q), sq = std::sin(q);
    double r = 0, z = 0, c = 1, s = 0;
    for (size_t j = 0; j < F.lengths.size(); ++j) {
      const double cn = c * cq - s * sq, sn = s * cq + c * sq;
      c = cn;
      s = sn;
      out[F.first_slot + j] = {r, z, c, s};
      r += F.lengths[j] * c;
      z += F.lengths[j] * s;
    }
  }
}

void ModelPoser::pose_model(const double* h, std::vector<Eigen::Vector3d>& out) const {
  Links L[kMaxSlots];
  links(h, L);
  out.resize(vertices_.size());
  for (size_t i = 0; i < vertices_.size(); ++i) {
    const Vertex& v = vertices_[i];
    const int f = slot_finger_[v.slot];
    if (f < 0) {
      out[i] = Eigen::Vector3d(v.a, v.b, 0);
      continue;
    }
    const Finger& F = fingers_[f];
    const Links& k = L[v.slot];
    const Eigen::Vector2d p = F.base + (k.hr + v.a * k.c) * F.dir + v.b * F.lateral;
    out[i] = Eigen::Vector3d(p.x(), p.y(), k.hz + v.a * k.s);
  }
}

void ModelPoser::project(const double* h, const Projection& mp, const std::vector<int>& which,
                         ProjectedMesh& out) const {
  const int planes = static_cast<int>(mp.clip_planes.size());
  const int rows = 3 + planes;
  if (planes > kMaxSensorPlanes) {
    throw Error("a projection may have at most " + std::to_string(kMaxSensorPlanes) + " clip planes, got " +
                std::to_string(planes));
  }
  // A point's image coordinates and plane values: rows of one linear map.
  Eigen::Vector4d A[kRows];
  for (int r = 0; r < 3; ++r) A[r] = mp.world_to_image.row(r).transpose();
  for (int p = 0; p < planes; ++p) A[3 + p] = mp.clip_planes[p];

  Links L[kMaxSlots];
  links(h, L);
  // Image and plane values of O, U, V per slot: origin, along, across.
  struct Frame {
    double o[kRows], u[kRows], v[kRows];
  };
  Frame frames[kMaxSlots];
  const Eigen::Vector4d ex(1, 0, 0, 0), ey(0, 1, 0, 0), ez(0, 0, 1, 0), e1(0, 0, 0, 1);
  for (int r = 0; r < rows; ++r) {
    frames[0].o[r] = A[r].dot(e1);
    frames[0].u[r] = A[r].dot(ex);
    frames[0].v[r] = A[r].dot(ey);
  }
  for (const Finger& F : fingers_) {
    double base[kRows], along[kRows], across[kRows], up[kRows];
    for (int r = 0; r < rows; ++r) {
      base[r] = A[r].dot(Eigen::Vector4d(F.base.x(), F.base.y(), 0, 1));
      along[r] = A[r].dot(Eigen::Vector4d(F.dir.x(), F.dir.y(), 0, 0));
      across[r] = A[r].dot(Eigen::Vector4d(F.lateral.x(), F.lateral.y(), 0, 0));
      up[r] = A[r].dot(ez);
    }
    for (size_t j = 0; j < F.lengths.size(); ++j) {
      const int slot = F.first_slot + static_cast<int>(j);
      const Links& k = L[slot];
      Frame& fr = frames[slot];
      for (int r = 0; r < rows; ++r) {
        fr.o[r] = base[r] + k.hr * along[r] + k.hz * up[r];
        fr.u[r] = k.c * along[r] + k.s * up[r];
        fr.v[r] = across[r];
      }
    }
  }

  const size_t n = which.size();
  out.image.resize(n);
  out.inside_planes.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Vertex& v = vertices_[which[i]];
    const Frame& fr = frames[v.slot];
    out.image[i] = Eigen::Vector3d(fr.o[0] + v.a * fr.u[0] + v.b * fr.v[0], fr.o[1] + v.a * fr.u[1] + v.b * fr.v[1],
                                   fr.o[2] + v.a * fr.u[2] + v.b * fr.v[2]);
    bool inside = true;
    for (int r = 3; r < rows; ++r) inside &= fr.o[r] + v.a * fr.u[r] + v.b * fr.v[r] >= 0;
    out.inside_planes[i] = inside;
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
