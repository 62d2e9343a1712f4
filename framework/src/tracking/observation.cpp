// Segmentation into the observation O, with the temporal prior (paper 2.1, 3).
#include "gtrack/observation.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "gtrack/error.hpp"

namespace gtrack {

Segmenter::Segmenter(ObservationConfig config, ImageSize image, ImageSize render)
    : config_(std::move(config)), image_(image), render_(render) {
  if (image_.width <= 0 || image_.height <= 0 || render_.width <= 0 || render_.height <= 0) {
    throw Error("segmenter: image and render sizes must be positive");
  }
}

cv::Mat Segmenter::segment(const cv::Mat& frame, std::optional<cv::Rect> roi) const {
  if (frame.cols != image_.width || frame.rows != image_.height || frame.type() != CV_8UC3) {
    throw InputError("observation: expected a " + std::to_string(image_.width) + "x" + std::to_string(image_.height) +
                     " BGR image of 8 bits a channel (3 channels), got " + std::to_string(frame.cols) + "x" +
                     std::to_string(frame.rows) + " with " + std::to_string(frame.channels()) +
                     (frame.channels() == 1 ? " channel" : " channels") + " of " +
                     std::to_string(8 * frame.elemSize1()) + " bits (convert it with cv::cvtColor and convertTo first)");
  }
  const cv::Rect full(0, 0, image_.width, image_.height);
  const cv::Rect area = roi ? (*roi & full) : full;
  cv::Mat mask = cv::Mat::zeros(image_.height, image_.width, CV_8U);
  if (area.area() == 0) return mask;
  const cv::Mat src = frame(area);
  cv::Mat part;
  const ObservationConfig& c = config_;
  if (c.color_space == "luminance") {
    cv::Mat grey;
    cv::cvtColor(src, grey, cv::COLOR_BGR2GRAY);
    cv::inRange(grey, cv::Scalar(c.luminance_min), cv::Scalar(c.luminance_max), part);
  } else {
    cv::Mat hsv;
    cv::cvtColor(src, hsv, cv::COLOR_BGR2HSV);
    if (c.hue_min <= c.hue_max) {
      cv::inRange(hsv, cv::Scalar(c.hue_min, c.saturation_min, c.value_min),
                  cv::Scalar(c.hue_max, c.saturation_max, c.value_max), part);
    } else {
      // hue_min > hue_max: a range that wraps through 0 (reds).
      cv::Mat lo, hi;
      cv::inRange(hsv, cv::Scalar(c.hue_min, c.saturation_min, c.value_min),
                  cv::Scalar(180, c.saturation_max, c.value_max), hi);
      cv::inRange(hsv, cv::Scalar(0, c.saturation_min, c.value_min),
                  cv::Scalar(c.hue_max, c.saturation_max, c.value_max), lo);
      cv::bitwise_or(lo, hi, part);
    }
  }
  if (c.open_kernel_px > 1) {
    const cv::Mat k = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(c.open_kernel_px, c.open_kernel_px));
    cv::morphologyEx(part, part, cv::MORPH_OPEN, k);
  }
  part.copyTo(mask(area));
  for (const cv::Rect& r : c.exclude_px) mask(r & full).setTo(0);
  return mask;
}

Observation Segmenter::observe(const cv::Mat& frame, const ObservationPrior* prior) const {
  const double sx = static_cast<double>(render_.width) / image_.width;
  const double sy = static_cast<double>(render_.height) / image_.height;
  const bool have_prior = prior && !prior->previous_mask.empty() && cv::countNonZero(prior->previous_mask) > 0;
  const double widen = have_prior ? std::max(1.0, prior->margin_scale) : 1.0;

  Observation obs;
  obs.roi = cv::Rect(0, 0, image_.width, image_.height);
  if (have_prior && config_.roi) {
    const cv::Rect box = cv::boundingRect(prior->previous_mask);
    const double m = config_.roi_margin_px * widen;
    // Clamped to the image before the cast: a wide margin, widened by lost
    // frames, is the whole image, not an int's overflow.
    const auto at = [](double v, int side) { return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(side))); };
    const int x0 = at(std::floor(box.x / sx - m), image_.width), y0 = at(std::floor(box.y / sy - m), image_.height);
    const int x1 = at(std::ceil((box.x + box.width) / sx + m), image_.width);
    const int y1 = at(std::ceil((box.y + box.height) / sy + m), image_.height);
    obs.roi = cv::Rect(x0, y0, x1 - x0, y1 - y0) & cv::Rect(0, 0, image_.width, image_.height);
  }
  const cv::Mat full = segment(frame, obs.roi);

  if (render_.width == image_.width && render_.height == image_.height) {
    obs.mask = full;
  } else {
    cv::Mat small;
    cv::resize(full, small, cv::Size(render_.width, render_.height), 0, 0, cv::INTER_AREA);
    // INTER_AREA averages: a render pixel is set when enough of its area is.
    // Any area at all is the limit of a small threshold: a negative one
    // would set every pixel.
    cv::threshold(small, obs.mask, std::max(0.0, config_.downscale_threshold * 255.0 - 0.5), 255, cv::THRESH_BINARY);
  }
  obs.detected = static_cast<std::uint64_t>(cv::countNonZero(obs.mask));

  if (have_prior && config_.prior && obs.detected > 0) {
    // Distance of every observed pixel to the previous model:
    // distanceTransform measures to the nearest zero, so the model's pixels
    // are the zeros. Taken within the box of both (the exact transform's
    // distances do not depend on pixels past the nearest zero), not over
    // the whole render image.
    const cv::Rect box = cv::boundingRect(prior->previous_mask) | cv::boundingRect(obs.mask);
    cv::Mat outside, dist;
    cv::compare(prior->previous_mask(box), 0, outside, cv::CMP_EQ);
    cv::distanceTransform(outside, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    const double sigma_render = config_.prior_sigma_px * widen * 0.5 * (sx + sy);
    // p = exp(-d^2 / 2 sigma^2) >= threshold  <=>  d <= sigma sqrt(-2 ln threshold).
    const double max_d = sigma_render * std::sqrt(-2.0 * std::log(config_.prior_threshold));
    cv::Mat near = cv::Mat::zeros(obs.mask.size(), CV_8U);
    cv::Mat near_box = near(box);
    cv::compare(dist, max_d, near_box, cv::CMP_LE);
    cv::bitwise_and(obs.mask, near, obs.mask);
  }
  obs.count = static_cast<std::uint64_t>(cv::countNonZero(obs.mask));
  return obs;
}

cv::Mat occlusion_rim(const cv::Mat& observed, int width_px) {
  if (width_px <= 0) return {};
  cv::Mat rim;
  cv::dilate(observed, rim, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * width_px + 1, 2 * width_px + 1)));
  rim.setTo(0, observed);
  return rim;
}

}  // namespace gtrack
