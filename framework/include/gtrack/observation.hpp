// The observation O: the gripper's pixels in one frame (paper 2.1 and 3).
//
// Camera frames are converted BGR -> HSV and bounded on H (optional), S and
// V; ultrasound frames are reduced to luminance and bounded. A morphological
// opening removes speckle. The full-resolution mask is then reduced to the
// renderer's size with INTER_AREA and thresholded, so O and the hypotheses
// P are compared pixel for pixel.
//
// Temporal continuity, given the previous estimate's rendered mask P_t:
//   - ROI: only the bounding box of P_t (full-resolution pixels), grown by
//     roi_margin_px, is segmented; the rest of O is empty;
//   - prior: each detected pixel's probability of belonging to the gripper is
//     p(O_t+1 | P_t) = exp(-d^2 / (2 sigma^2)), d = its distance (in
//     full-resolution pixels, from a distance transform at render size) to
//     the nearest pixel of P_t; pixels with p below prior_threshold are
//     dropped, i.e. those farther than sigma * sqrt(-2 ln threshold).
// With no previous estimate (first frame, recovery) the whole image is used.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>

#include "gtrack/engine_config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack {

struct Observation {
  cv::Mat mask;            // CV_8U, 0/255 at render size: O
  std::uint64_t count = 0; // |O|
  cv::Rect roi;            // full-resolution region that was searched
  std::uint64_t detected = 0;  // render pixels before the temporal prior
  bool empty() const { return count == 0; }
};

// The occlusion rim of an observation mask (CV_8U, non-zero = observed):
// the pixels within width_px of it (a (2 width_px + 1)-square dilation),
// outside it, as 0/255; an empty Mat when width_px <= 0. The occlusion
// budget never takes rendered pixels there as hidden (cost.hpp).
GTRACK_API cv::Mat occlusion_rim(const cv::Mat& observed, int width_px);

// What the previous frame says about this one.
struct ObservationPrior {
  cv::Mat previous_mask;  // CV_8U at render size: P_t = f(g^_t, C)
  double margin_scale = 1;  // >1 widens the ROI and the prior (after lost frames)
};

class GTRACK_API Segmenter {
 public:
  Segmenter(ObservationConfig config, ImageSize image, ImageSize render);

  // Full-resolution binary mask (0/255) of the gripper colour, opened; only
  // inside `roi` when given.
  cv::Mat segment(const cv::Mat& frame, std::optional<cv::Rect> roi = {}) const;
  // The observation at render size, with the ROI and prior applied when given.
  Observation observe(const cv::Mat& frame, const ObservationPrior* prior = nullptr) const;

  const ObservationConfig& config() const { return config_; }

 private:
  ObservationConfig config_;
  ImageSize image_, render_;
};

}  // namespace gtrack
