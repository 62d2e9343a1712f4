// Smooth random functions of time for synthetic trajectories.
//
// A path is a sum of a few sinusoids with random frequencies (between the
// base frequency and three times it) and phases, scaled so that its largest
// magnitude over the sampled frames is exactly 1: a preset's amplitude is
// then the peak the sequence really reaches, whatever its length.
#pragma once

#include <random>
#include <vector>

namespace gtrack::synth {

class SmoothPath {
 public:
  SmoothPath(std::mt19937_64& rng, double base_hz, int components = 3);
  double raw(double t) const;
  // Samples raw() at the frame times and rescales to a peak of exactly 1.
  std::vector<double> sample(const std::vector<double>& times) const;

 private:
  std::vector<double> freq_, phase_, amp_;
};

// 0 below a, 1 above b, C1-smooth in between.
double smoothstep(double a, double b, double x);

}  // namespace gtrack::synth
