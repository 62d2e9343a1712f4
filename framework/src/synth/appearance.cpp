#include "synth/appearance.hpp"

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

}  // namespace gtrack::synth
