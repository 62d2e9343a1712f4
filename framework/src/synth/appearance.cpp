#include "synth/appearance.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <tuple>

namespace gtrack::synth {

cv::Vec3f bgr_from_hsv(const cv::Vec3d& hsv) {
  cv::Mat in(1, 1, CV_32FC3, cv::Scalar(hsv[0] * 2, hsv[1] / 255.0, hsv[2] / 255.0)), out;
  cv::cvtColor(in, out, cv::COLOR_HSV2BGR);  // float HSV: H in degrees, S, V in [0, 1]
  return out.at<cv::Vec3f>(0, 0) * 255.0f;
}

namespace {

// Sum of noise octaves: coarse blotches plus finer grain, roughly unit spread.
cv::Mat octave_noise(cv::RNG& rng, cv::Size size) {
  cv::Mat acc = cv::Mat::zeros(size, CV_32F);
  double weight = 1, total = 0;
  for (int cell : {96, 32, 10, 4}) {
    cv::Mat small(std::max(2, size.height / cell + 2), std::max(2, size.width / cell + 2), CV_32F), big;
    rng.fill(small, cv::RNG::NORMAL, 0, 1);
    cv::resize(small, big, size, 0, 0, cv::INTER_CUBIC);
    acc += weight * big;
    total += weight * weight;
    weight *= 0.55;
  }
  return acc / std::sqrt(total);
}

cv::Mat make_background(std::uint64_t seed, const SynthPreset& p, cv::Size size) {
  cv::RNG rng(seed * 7919 + 3);
  const cv::Mat value = octave_noise(rng, size), sat = octave_noise(rng, size);
  std::vector<cv::Mat> hsv(3);
  hsv[0] = cv::Mat(size, CV_32F, cv::Scalar(p.tissue_hsv[0] * 2));
  // Saturation varies little: tissue stays well below the segmentation bound.
  hsv[1] = (p.tissue_hsv[1] + 3.0 * sat) / 255.0;
  hsv[2] = (p.tissue_hsv[2] * (1.0 + p.tissue_contrast * value)) / 255.0;
  cv::max(hsv[1], 0.0, hsv[1]);
  cv::min(hsv[2], 1.0, hsv[2]);
  cv::Mat merged, bgr;
  cv::merge(hsv, merged);
  cv::cvtColor(merged, bgr, cv::COLOR_HSV2BGR);
  return bgr * 255.0;
}

}  // namespace

std::shared_ptr<const cv::Mat> tissue_background(std::uint64_t seed, const SynthPreset& preset, cv::Size size,
                                                 int margin) {
  static std::mutex mutex;
  static std::map<std::tuple<std::uint64_t, std::string, int, int, int>, std::shared_ptr<const cv::Mat>> cache;
  const auto key = std::make_tuple(seed, preset.name, size.width, size.height, margin);
  std::lock_guard lock(mutex);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  if (cache.size() > 4) cache.clear();  // sweeps make a few sequences; keep memory bounded
  auto bg = std::make_shared<const cv::Mat>(
      make_background(seed, preset, {size.width + 2 * margin, size.height + 2 * margin}));
  cache[key] = bg;
  return bg;
}

cv::Mat degrade(cv::Mat& image, double blur_sigma_px, const SynthPreset& p, std::uint64_t frame_seed) {
  cv::RNG rng(frame_seed);
  if (blur_sigma_px > 0.05) cv::GaussianBlur(image, image, cv::Size(), blur_sigma_px);
  const cv::Scalar gain(1 + p.colour_jitter * rng.gaussian(1), 1 + p.colour_jitter * rng.gaussian(1),
                        1 + p.colour_jitter * rng.gaussian(1));
  cv::multiply(image, gain, image);
  cv::Mat noise(image.size(), CV_32FC3);
  rng.fill(noise, cv::RNG::NORMAL, 0, p.noise_sigma);
  image += noise;
  cv::Mat out;
  image.convertTo(out, CV_8UC3);  // saturates to 0..255
  return out;
}

cv::Mat lens_map(const Sensor& sensor) {
  const Projection linear = sensor.projection();
  const Eigen::Matrix<double, 3, 4>& m = linear.world_to_image;
  const Eigen::Vector3d axis = viewing_axis(linear), nominal = sensor.nominal_position_mm();
  // The linear image's pixel (u, v) (centres at +0.5) on the nominal plane,
  // then where the full model draws that point.
  const auto drawn_at = [&](const Eigen::Vector2d& uv) -> std::optional<Eigen::Vector2d> {
    Eigen::Matrix3d a;
    Eigen::Vector3d b;
    a.row(0) = (m.row(0) - uv.x() * m.row(2)).head<3>();
    a.row(1) = (m.row(1) - uv.y() * m.row(2)).head<3>();
    a.row(2) = axis.transpose();
    b << -(m(0, 3) - uv.x() * m(2, 3)), -(m(1, 3) - uv.y() * m(2, 3)), axis.dot(nominal);
    const Eigen::Vector3d x = a.fullPivLu().solve(b);
    if (!x.allFinite()) return std::nullopt;
    return sensor.project(x);
  };
  const ImageSize size = sensor.image_size();
  const int w = size.width, h = size.height;
  // Is there any? A 9 x 9 sample of the image.
  double worst = 0;
  for (int i = 0; i <= 8; ++i) {
    for (int j = 0; j <= 8; ++j) {
      const Eigen::Vector2d uv(w * i / 8.0, h * j / 8.0);
      const auto d = drawn_at(uv);
      worst = std::max(worst, d ? (*d - uv).norm() : 1.0);
    }
  }
  if (worst < 0.01) return {};
  // The inverse, on a grid every kStep pixels (the distortion is smooth):
  // the linear pixel u that the lens draws at d, by fixed-point steps
  // u += d - drawn_at(u); then interpolated to every pixel.
  constexpr int kStep = 8;
  const int gw = (w - 1) / kStep + 2, gh = (h - 1) / kStep + 2;
  cv::Mat grid(gh, gw, CV_64FC2);
  for (int gy = 0; gy < gh; ++gy) {
    for (int gx = 0; gx < gw; ++gx) {
      const Eigen::Vector2d d(gx * kStep + 0.5, gy * kStep + 0.5);
      Eigen::Vector2d u = d;
      bool converged = false;
      for (int it = 0; it < 50 && !converged; ++it) {
        const auto f = drawn_at(u);
        if (!f) break;
        const Eigen::Vector2d step = d - *f;
        u += step;
        converged = step.norm() < 1e-3;
      }
      // Where the lens model folds back (a strong barrel's corners), no
      // point of the linear image is drawn there: far outside, so that the
      // frame's border repeats.
      if (!converged) u = Eigen::Vector2d(-1e6, -1e6);
      grid.at<cv::Vec2d>(gy, gx) = cv::Vec2d(u.x() - 0.5, u.y() - 0.5);  // OpenCV's pixel centres
    }
  }
  cv::Mat map(h, w, CV_32FC2);
  for (int y = 0; y < h; ++y) {
    const int gy = y / kStep;
    const double fy = (y - gy * kStep) / double(kStep);
    for (int x = 0; x < w; ++x) {
      const int gx = x / kStep;
      const double fx = (x - gx * kStep) / double(kStep);
      const cv::Vec2d p = (1 - fy) * ((1 - fx) * grid.at<cv::Vec2d>(gy, gx) + fx * grid.at<cv::Vec2d>(gy, gx + 1)) +
                          fy * ((1 - fx) * grid.at<cv::Vec2d>(gy + 1, gx) + fx * grid.at<cv::Vec2d>(gy + 1, gx + 1));
      map.at<cv::Vec2f>(y, x) = cv::Vec2f(static_cast<float>(p[0]), static_cast<float>(p[1]));
    }
  }
  return map;
}

}  // namespace gtrack::synth
