// The pieces of project_and_clip that the cpu backend reuses on its fast path.
//
// project_and_clip treats one triangle at a time. The cpu backend first
// checks whether a whole convex face (the palm, a link) is inside every
// plane; if so it projects the face's vertices with project() below and
// skips clipping, and otherwise it hands each triangle to clip_triangle(),
// so a face that needs clipping gives exactly what project_and_clip gives.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "gtrack/renderer.hpp"

namespace gtrack::render {

// Clip planes a projection may carry (sensors use one or two).
inline constexpr int kMaxSensorPlanes = 8;

// The region every polygon is clipped to besides the sensor's planes, in
// homogeneous image coordinates (u*w, v*w, w): w above a tiny positive
// limit, and u, v within a guard band of one image size around the image.
// Beyond kFarW, u_hi * w may overflow: such a vertex (a configuration sent
// absurdly far, inf, nan) is never inside, and clip_triangle drops it.
inline constexpr double kFarW = 1e200;
struct Frustum {
  double u_lo, u_hi, v_lo, v_hi, w_min;
  bool contains(const Eigen::Vector3d& h) const {
    const double w = h.z();
    // Non-short-circuit: almost every vertex is inside, and branches cost more than the compares.
    return (w >= w_min) & (w <= kFarW) & (h.x() >= u_lo * w) & (h.x() <= u_hi * w) & (h.y() >= v_lo * w) &
           (h.y() <= v_hi * w);
  }
};

Frustum frustum_of(const Projection& projection);

inline Eigen::Vector3d project(const Projection& p, const Eigen::Vector3d& x) {
  return p.world_to_image.leftCols<3>() * x + p.world_to_image.col(3);
}

inline double plane_value(const Eigen::Vector4d& plane, const Eigen::Vector3d& x) {
  return plane.head<3>().dot(x) + plane.w();
}

inline Eigen::Vector2d dehomogenise(const Eigen::Vector3d& h) {
  const double inv_w = 1.0 / h.z();
  return {h.x() * inv_w, h.y() * inv_w};
}

// Clips one triangle against the projection's planes and `frustum`, projects
// it and appends the result (nothing, or one polygon, or a fan split of one)
// to `out`. Throws gtrack::Error if the projection has too many planes.
void clip_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Projection& projection, const Frustum& frustum, std::vector<ScreenPolygon>& out);

// Appends a convex polygon already known to be inside everything, given in
// homogeneous image coordinates, splitting it to fit ScreenPolygon.
void emit_projected(const Eigen::Vector3d* h, int n, std::vector<ScreenPolygon>& out);

}  // namespace gtrack::render
