// Anti-aliased drawing by supersampling, for synthetic frames.
//
// Convex polygons in full-resolution pixel coordinates are filled into a
// buffer that covers a region of interest at `ss` x `ss` samples per pixel,
// with the pixel-centre rule at sample level (no edge inflation as with
// cv::fillConvexPoly, which would bias the drawn outline outwards). The
// buffer is then averaged down to a coverage in [0, 1] per pixel.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>

namespace gtrack::synth {

struct SampleGrid {
  cv::Rect roi;  // full-resolution pixels
  int ss = 4;    // samples per pixel side
  cv::Mat buf;   // CV_8U, roi.height*ss x roi.width*ss

  SampleGrid(cv::Rect roi, int ss);
  // Writes `value` (non-zero) into every sample inside the polygon.
  void fill_convex(const Eigen::Vector2d* v, int n, std::uint8_t value);
  // Per pixel of roi: share of samples set (CV_32F in [0, 1]) and, where set,
  // the mean of their values (CV_32F).
  void resolve(cv::Mat& coverage, cv::Mat* mean_value = nullptr) const;
};

// Bounding box (full-resolution pixels, grown to whole pixels) of polygons.
cv::Rect bounding_rect(const Eigen::Vector2d* v, int n);

}  // namespace gtrack::synth
