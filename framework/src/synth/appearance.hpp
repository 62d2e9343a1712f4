// What a synthetic frame looks like apart from the gripper's geometry:
// the tissue background, colours, and the sensor's degradations.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>

#include "gtrack/synth.hpp"

namespace gtrack::synth {

// A BGR colour (float, 0..255) from OpenCV-unit HSV.
cv::Vec3f bgr_from_hsv(const cv::Vec3d& hsv);

// Tissue-like texture (smooth multi-scale noise in value, a little in
// saturation), larger than the image by `margin` on each side so that the
// view can drift over it. CV_32FC3 BGR. Shared between frames: built once
// per (seed, preset, size) and cached.
std::shared_ptr<const cv::Mat> tissue_background(std::uint64_t seed, const SynthPreset& preset, cv::Size size,
                                                 int margin);

// Defocus blur, per-channel gain jitter and Gaussian sensor noise, in place
// on a CV_32FC3 image; then rounded to CV_8UC3.
cv::Mat degrade(cv::Mat& image, double blur_sigma_px, const SynthPreset& preset, std::uint64_t frame_seed);

}  // namespace gtrack::synth
