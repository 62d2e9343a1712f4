// The oracle: one point-in-triangle test per pixel centre and triangle.
#include "support/reference_raster.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace gtrack::testing {

namespace {

struct Point {
  std::int64_t x, y;  // 1/256 pixel
};

Point to_fixed(const Eigen::Vector2d& p) {
  // The default floating-point rounding mode is to nearest, ties to even.
  return {static_cast<std::int64_t>(std::nearbyint(p.x() * 256.0)),
          static_cast<std::int64_t>(std::nearbyint(p.y() * 256.0))};
}

// Which side of the line p -> q the point s is on (sign only matters).
std::int64_t side(const Point& p, const Point& q, const Point& s) {
  return (q.x - p.x) * (s.y - p.y) - (q.y - p.y) * (s.x - p.x);
}

// Is the edge p-q of a triangle whose third vertex is r a top or a left edge?
bool top_or_left(Point p, Point q, const Point& r) {
  if (p.y == q.y) return r.y > p.y;  // horizontal: top when the triangle lies below it (y down)
  if (p.y > q.y) std::swap(p, q);   // walk the edge downwards
  // Walking down the screen, the triangle is on the right when r is on the
  // negative side of p -> q (y down flips the usual sense).
  return side(p, q, r) < 0;
}

// The centre s belongs to the triangle's side of edge p-q (third vertex r).
bool inside_edge(const Point& p, const Point& q, const Point& r, const Point& s) {
  const std::int64_t ss = side(p, q, s), sr = side(p, q, r);
  if (ss == 0) return top_or_left(p, q, r);
  return (ss > 0) == (sr > 0);
}

void fill_triangle(const Point& a, const Point& b, const Point& c, cv::Mat& out) {
  if (side(a, b, c) == 0) return;  // no area, no pixels
  // Pixel bounding box, generous: the exact test below decides.
  const double xmin = std::min({a.x, b.x, c.x}) / 256.0, xmax = std::max({a.x, b.x, c.x}) / 256.0;
  const double ymin = std::min({a.y, b.y, c.y}) / 256.0, ymax = std::max({a.y, b.y, c.y}) / 256.0;
  const int i0 = std::max(0, static_cast<int>(std::floor(xmin)) - 1);
  const int i1 = std::min(out.cols - 1, static_cast<int>(std::ceil(xmax)) + 1);
  const int j0 = std::max(0, static_cast<int>(std::floor(ymin)) - 1);
  const int j1 = std::min(out.rows - 1, static_cast<int>(std::ceil(ymax)) + 1);
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      const Point s{256 * static_cast<std::int64_t>(i) + 128, 256 * static_cast<std::int64_t>(j) + 128};
      if (inside_edge(a, b, c, s) && inside_edge(b, c, a, s) && inside_edge(c, a, b, s)) {
        out.at<std::uint8_t>(j, i) = 255;
      }
    }
  }
}

}  // namespace

cv::Mat reference_raster(const std::vector<ScreenPolygon>& polygons, ImageSize size) {
  cv::Mat out(size.height, size.width, CV_8UC1, cv::Scalar(0));
  for (const ScreenPolygon& poly : polygons) {
    for (int k = 1; k + 1 < poly.count; ++k) {
      fill_triangle(to_fixed(poly.v[0]), to_fixed(poly.v[k]), to_fixed(poly.v[k + 1]), out);
    }
  }
  return out;
}

cv::Mat reference_mask(const ArticulatedModel& model, const Projection& render_projection,
                       const Eigen::VectorXd& hypothesis) {
  std::vector<Eigen::Vector3d> world;
  model.pose(hypothesis, world);
  std::vector<ScreenPolygon> polygons;
  project_and_clip(world, render_projection, polygons);
  return reference_raster(polygons, render_projection.size);
}

GripperGeometry hydrogel_geometry() {
  RadialGripperSpec spec;
  spec.name = "hydrogel_test";
  spec.fingers = 6;
  spec.palm_sides = 6;
  spec.palm_circumradius_mm = 0.65 / std::cos(std::numbers::pi / 6);  // apothem 0.65 mm
  const double lengths[] = {0.35, 0.35, 0.35, 0.30};
  const double widths[] = {0.60, 0.55, 0.50, 0.45, 0.0};
  for (int j = 0; j < 4; ++j) spec.links.push_back({lengths[j], widths[j], widths[j + 1]});
  GripperGeometry g = make_radial_gripper(spec);
  g.joint_min_deg = -10;
  g.joint_max_deg = 80;
  g.unfolded_deg = 0;
  g.folded_deg = 60;
  return g;
}

Projection microscope_projection(int width, int height, double fx, double fy, double cx, double cy,
                                 double near_mm) {
  Projection p;
  p.size = {width, height};
  p.world_to_image << fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0;
  p.clip_planes.push_back(Eigen::Vector4d(0, 0, 1, -near_mm));
  return p;
}

}  // namespace gtrack::testing
