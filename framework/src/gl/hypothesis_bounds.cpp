// Conservative screen boxes of hypotheses.
#include "gl/hypothesis_bounds.hpp"

#include <algorithm>
#include <cmath>

namespace gtrack::gl {

void PixelBox::unite(const PixelBox& b) {
  if (b.empty()) return;
  if (empty()) {
    *this = b;
    return;
  }
  x0 = std::min(x0, b.x0);
  y0 = std::min(y0, b.y0);
  x1 = std::max(x1, b.x1);
  y1 = std::max(y1, b.y1);
}

double model_reach_mm(const ArticulatedModel& model) {
  const GripperGeometry& g = model.geometry();
  double reach = 0;
  for (const ModelVertex& v : model.mesh()) {
    if (v.finger < 0) {
      reach = std::max(reach, std::hypot(double(v.a), double(v.b)));
      continue;
    }
    const FingerShape& f = g.fingers[static_cast<size_t>(v.finger)];
    double r = f.base_mm.norm() + std::abs(double(v.a)) + std::abs(double(v.b));
    for (int j = 0; j < v.link; ++j) r += f.links[static_cast<size_t>(j)].length_mm;
    reach = std::max(reach, r);
  }
  return reach;
}

PixelBox hypothesis_box(const Projection& projection, const Eigen::Vector3d& centre, double reach) {
  const PixelBox full{0, 0, projection.size.width, projection.size.height};
  // A centre that is not a number draws nothing (its triangles are dropped).
  if (!centre.allFinite()) return {};
  for (const Eigen::Vector4d& plane : projection.clip_planes) {
    const double n = plane.head<3>().norm();
    if (n > 0 && plane.head<3>().dot(centre) + plane.w() < -reach * n) return {};
  }
  const Eigen::Matrix<double, 3, 4>& m = projection.world_to_image;
  const double w_min = 1e-9 * m.row(2).cwiseAbs().sum();
  double u_lo = INFINITY, u_hi = -INFINITY, v_lo = INFINITY, v_hi = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p = centre + reach * Eigen::Vector3d(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1,
                                                               corner & 4 ? 1 : -1);
    const Eigen::Vector3d h = m.leftCols<3>() * p + m.col(3);
    if (!(h.z() > w_min)) return full;  // the cube reaches behind the camera
    const double u = h.x() / h.z(), v = h.y() / h.z();
    u_lo = std::min(u_lo, u);
    u_hi = std::max(u_hi, u);
    v_lo = std::min(v_lo, v);
    v_hi = std::max(v_hi, v);
  }
  // Pixel i is lit when i + 0.5 is inside; one pixel of margin absorbs the
  // float arithmetic of the GPU.
  auto lo = [](double a, int size) { return static_cast<int>(std::clamp(std::floor(a - 0.5) - 1.0, 0.0, double(size))); };
  auto hi = [](double a, int size) { return static_cast<int>(std::clamp(std::ceil(a - 0.5) + 2.0, 0.0, double(size))); };
  PixelBox b{lo(u_lo, full.x1), lo(v_lo, full.y1), hi(u_hi, full.x1), hi(v_hi, full.y1)};
  if (b.empty()) return {};
  return b;
}

}  // namespace gtrack::gl
