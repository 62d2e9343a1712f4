// Projection scaling and the posed-triangle -> screen-polygon step that every
// rasteriser in gtrack consumes.
//
// Besides the sensor's own clip planes, each polygon is clipped against a
// guard band around the render target (and w > 0). Nothing inside the image
// changes, but screen coordinates stay within a few image sizes, which is
// what lets the rasterisers use exact 64-bit fixed-point edge functions.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <type_traits>

#include "gtrack/error.hpp"
#include "gtrack/renderer.hpp"
#include "render/clip.hpp"

namespace gtrack {

namespace render {

namespace {

// Planes (sensor + frustum) a triangle may be cut by; each adds at most one vertex.
constexpr int kFrustumPlanes = 5;
constexpr int kMaxVertices = 3 + kMaxSensorPlanes + kFrustumPlanes;

using Poly3 = std::array<Eigen::Vector3d, kMaxVertices>;

// Sutherland-Hodgman against one half-space value(p) >= 0. `value` is
// evaluated once per vertex; the cut point is interpolated linearly, which is
// exact for any function linear in p (planes in world or homogeneous space).
template <class Value>
int clip_polygon(const Poly3& in, int n, Poly3& out, Value value) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& a = in[i];
    const Eigen::Vector3d& b = in[(i + 1) % n];
    const double va = value(a), vb = value(b);
    if (va >= 0) out[m++] = a;
    if ((va >= 0) != (vb >= 0)) {
      const double t = va / (va - vb);
      out[m++] = a + t * (b - a);
    }
  }
  return m;
}

}  // namespace

Frustum frustum_of(const Projection& projection) {
  const double width = projection.size.width, height = projection.size.height;
  const double guard = std::max(width, height);
  // Below this w, 1/w would leave the guard band anyway.
  const double w_min = 1e-12 * projection.world_to_image.row(2).cwiseAbs().sum();
  return {-guard, width + guard, -guard, height + guard, w_min};
}

void emit_projected(const Eigen::Vector3d* h, int n, std::vector<ScreenPolygon>& out) {
  if (n < 3) return;
  // A fan split keeps every piece within ScreenPolygon's fixed capacity.
  constexpr int cap = static_cast<int>(std::extent_v<decltype(ScreenPolygon::v)>);
  int start = 1;
  while (start + 1 < n) {
    // Built here and copied: emplace_back() would zero the whole array first.
    ScreenPolygon p;
    p.count = 0;
    p.v[p.count++] = dehomogenise(h[0]);
    const int end = std::min(n, start + cap - 1);
    for (int i = start; i < end; ++i) p.v[p.count++] = dehomogenise(h[i]);
    out.push_back(p);
    start = end - 1;
  }
}

void clip_triangle(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                   const Projection& projection, const Frustum& f, std::vector<ScreenPolygon>& out) {
  const auto& planes = projection.clip_planes;
  if (planes.size() > kMaxSensorPlanes) {
    throw Error("a projection may have at most " + std::to_string(kMaxSensorPlanes) + " clip planes, got " +
                std::to_string(planes.size()));
  }
  Poly3 a, b;
  int n = 3;
  a[0] = x0, a[1] = x1, a[2] = x2;

  // Sensor planes, in world coordinates.
  for (const Eigen::Vector4d& pl : planes) {
    auto value = [&](const Eigen::Vector3d& x) { return plane_value(pl, x); };
    bool all_in = true;
    for (int i = 0; i < n && all_in; ++i) all_in = value(a[i]) >= 0;
    if (all_in) continue;
    n = clip_polygon(a, n, b, value);
    std::swap(a, b);
    if (n < 3) return;
  }

  // To homogeneous image coordinates: linear in x, so the frustum planes can
  // be clipped here with the same result as in world coordinates.
  bool all_in = true;
  for (int i = 0; i < n; ++i) {
    a[i] = project(projection, a[i]);
    // Clipping it would overflow to inf - inf (and nan is nowhere).
    if (!(a[i].cwiseAbs().maxCoeff() <= kFarW)) return;
    all_in = all_in && f.contains(a[i]);
  }
  if (!all_in) {
    const std::array<Eigen::Vector3d, 4> sides{Eigen::Vector3d(1, 0, -f.u_lo), Eigen::Vector3d(-1, 0, f.u_hi),
                                               Eigen::Vector3d(0, 1, -f.v_lo), Eigen::Vector3d(0, -1, f.v_hi)};
    n = clip_polygon(a, n, b, [&](const Eigen::Vector3d& h) { return h.z() - f.w_min; });
    std::swap(a, b);
    for (const auto& s : sides) {
      if (n < 3) return;
      n = clip_polygon(a, n, b, [&](const Eigen::Vector3d& h) { return s.dot(h); });
      std::swap(a, b);
    }
  }
  emit_projected(a.data(), n, out);
}

}  // namespace render

std::string render_scale_problem(ImageSize size, double scale) {
  const long w = std::lround(scale * size.width), h = std::lround(scale * size.height);
  if (std::min(w, h) >= 8) return "";
  return "renders the " + std::to_string(size.width) + "x" + std::to_string(size.height) + " image at " +
         std::to_string(std::max(1L, w)) + "x" + std::to_string(std::max(1L, h)) +
         " pixels; expected a scale that keeps at least 8 pixels on each side";
}

Projection scaled_projection(const Projection& projection, double scale) {
  if (!(scale > 0)) throw Error("render scale must be positive, got " + std::to_string(scale));
  Projection p = projection;
  p.size.width = std::max(1, static_cast<int>(std::lround(scale * projection.size.width)));
  p.size.height = std::max(1, static_cast<int>(std::lround(scale * projection.size.height)));
  // Pixel edges sit on integers in both images, so scaling u and v is exact.
  // Each axis by the ratio of the rounded sizes, the ratio the observation is
  // resized by: 1024 px at scale 0.3 is 307 render pixels, 0.2998 each.
  p.world_to_image.row(0) *= static_cast<double>(p.size.width) / projection.size.width;
  p.world_to_image.row(1) *= static_cast<double>(p.size.height) / projection.size.height;
  return p;
}

Projection padded_projection(const Projection& projection, int margin_x, int margin_y) {
  if (margin_x < 0 || margin_y < 0) throw Error("padded_projection: a margin cannot be negative");
  Projection p = projection;
  // u = r0.X / r2.X: adding m times the third row to the first adds m to u,
  // for a perspective (pinhole) and an affine (ultrasound slice) row alike.
  p.world_to_image.row(0) += margin_x * projection.world_to_image.row(2);
  p.world_to_image.row(1) += margin_y * projection.world_to_image.row(2);
  p.size.width += 2 * margin_x;
  p.size.height += 2 * margin_y;
  return p;
}

void project_and_clip(const std::vector<Eigen::Vector3d>& world_triangles, const Projection& projection,
                      std::vector<ScreenPolygon>& out) {
  out.clear();
  const render::Frustum f = render::frustum_of(projection);
  for (size_t t = 0; t + 2 < world_triangles.size(); t += 3) {
    render::clip_triangle(world_triangles[t], world_triangles[t + 1], world_triangles[t + 2], projection, f, out);
  }
}

}  // namespace gtrack
