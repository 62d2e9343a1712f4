#include "synth/smooth_path.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace gtrack::synth {

SmoothPath::SmoothPath(std::mt19937_64& rng, double base_hz, int components) {
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < components; ++k) {
    freq_.push_back(base_hz * (1 + 2 * u(rng)));
    phase_.push_back(2 * std::numbers::pi * u(rng));
    amp_.push_back(1.0 / (1 + k));  // slower components dominate: smooth, not jittery
  }
}

double SmoothPath::raw(double t) const {
  double v = 0;
  for (size_t k = 0; k < freq_.size(); ++k) v += amp_[k] * std::sin(2 * std::numbers::pi * freq_[k] * t + phase_[k]);
  return v;
}

std::vector<double> SmoothPath::sample(const std::vector<double>& times) const {
  std::vector<double> v;
  double peak = 1e-12;
  for (double t : times) {
    v.push_back(raw(t));
    peak = std::max(peak, std::abs(v.back()));
  }
  for (double& x : v) x /= peak;
  return v;
}

double smoothstep(double a, double b, double x) {
  const double s = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return s * s * (3 - 2 * s);
}

}  // namespace gtrack::synth
