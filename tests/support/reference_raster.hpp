// A brute-force rasteriser that the render backends are checked against,
// and a hydrogel-like scene that needs no plugin.
//
// The oracle tests every pixel centre against every triangle, one at a time,
// and takes the union. It shares no code with the cpu backend: only the
// definition of coverage is common (renderer.hpp):
//   - vertices snapped to 1/256 pixel, ties to even;
//   - pixel (i, j) covered when (i + 0.5, j + 0.5) is inside a triangle;
//   - a centre exactly on an edge counts only for a top edge (horizontal,
//     the triangle below it) or a left edge (the triangle to its right),
//     with image y pointing down.
// It is slow on purpose (clear, not clever) and is meant for test-sized images.
#pragma once

#include <Eigen/Core>
#include <gtrack/model.hpp>
#include <gtrack/renderer.hpp>
#include <gtrack/sensor.hpp>
#include <opencv2/core.hpp>
#include <vector>

namespace gtrack::testing {

// CV_8U, 0 / 255: the union of the polygons' fan triangles.
cv::Mat reference_raster(const std::vector<ScreenPolygon>& polygons, ImageSize size);

// Poses the model with ArticulatedModel::pose, clips and projects with
// project_and_clip, fills with reference_raster. `render_projection` is
// already at render resolution.
cv::Mat reference_mask(const ArticulatedModel& model, const Projection& render_projection,
                       const Eigen::VectorXd& hypothesis);

// The hydrogel gripper of the paper built directly: hexagonal palm (apothem
// 0.65 mm), six fingers of four links 0.35/0.35/0.35/0.30 mm, widths
// 0.60 -> 0.55 -> 0.50 -> 0.45 -> 0 (a pointed tip): 46 triangles, 4 mm tip to tip.
GripperGeometry hydrogel_geometry();

// A pinhole camera whose frame is the world frame (OpenCV axes), with pixel
// centres at +0.5 and a near plane z >= near_mm.
Projection microscope_projection(int width, int height, double fx, double fy, double cx, double cy,
                                 double near_mm = 0.1);

}  // namespace gtrack::testing
