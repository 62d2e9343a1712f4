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

// The sensor's lens distortion, as a map for cv::remap (CV_32FC2, OpenCV's
// pixel coordinates): for each pixel of a frame, where it lies in the image
// the linear projection draws. Found from Sensor::project, the full model,
// against Sensor::projection, the linear one, on the plane of the nominal
// position. Empty when the two agree within 0.01 pixels (no distortion).
cv::Mat lens_map(const Sensor& sensor);

// Defocus blur, per-channel gain jitter and Gaussian sensor noise, in place
// on a CV_32FC3 image; then rounded to CV_8UC3.
cv::Mat degrade(cv::Mat& image, double blur_sigma_px, const SynthPreset& preset, std::uint64_t frame_seed);

}  // namespace gtrack::synth
