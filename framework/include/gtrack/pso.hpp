// Particle Swarm Optimization as in the paper's Algorithm 1.
//
// For k = 1..G: every k_r-th generation one random parameter of a random
// subset of the swarm is re-drawn (partial randomisation); the N particles
// are evaluated as ONE batch; personal bests x^_i and the global best g^ are
// updated; then each particle moves with
//     v_i <- w v_i + c1_i r1 (x^_i - x_i) + c2_i r2 (g^ - x_i),   x_i <- x_i + v_i
// with the rank-adaptive coefficients c1_i = C/(N-1)^2 (rank_i - N)^2 and
// c2_i = C - c1_i, and is put back inside the bounds (periodic parameters
// wrap). r1, r2 are uniform in [0, 1], drawn per dimension.
//
// Rank convention: rank_i in 1..N orders the particles by the cost of their
// current configuration, rank 1 = lowest cost (best). So the best particle
// has c1 = C, c2 = 0 and searches around its own best, the worst has c1 = 0,
// c2 = C and moves straight toward g^: "particles in the lower rank [lower
// standing] move toward the global optimum, while particles in a higher rank
// are close to the best solution and search around it" (paper Section 3).
//
// Velocity clamping (an addition, off when max_velocity_fraction = 0): each
// component is limited to that fraction of the parameter's range, so that a
// particle cannot cross the whole box in one step. For periodic parameters
// (rz) the differences x^_i - x_i and g^ - x_i are taken the short way round.
//
// The optimizer works on any batch objective; minimize() wraps a plain
// function of one vector for tests and comparisons. Everything random comes
// from one std::mt19937_64 seeded by the caller: same seed, same result.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "gtrack/engine_config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/parameter_space.hpp"

namespace gtrack {

// Scores each column of `hypotheses` into `costs` (resized by the callee).
using BatchObjective = std::function<void(const Eigen::MatrixXd& hypotheses, Eigen::VectorXd& costs)>;

struct Swarm {
  Eigen::MatrixXd x;          // configurations x_i^k, one per column
  Eigen::MatrixXd v;          // velocities
  Eigen::VectorXd cost;       // E(x_i^k)
  Eigen::MatrixXd best_x;     // x^_i
  Eigen::VectorXd best_cost;  // E(x^_i)
  Eigen::VectorXd g;          // g^
  double g_cost = 0;
  std::vector<int> rank;      // rank_i in 1..N, 1 = best current cost
  int size() const { return static_cast<int>(x.cols()); }
};

struct PsoResult {
  Eigen::VectorXd best;
  double best_cost = 0;
  std::uint64_t evaluations = 0;
  std::vector<double> best_cost_per_generation;
};

// Observes the swarm after each generation's velocity update (k from 1).
using GenerationHook = std::function<void(int k, const Swarm& swarm)>;

class GTRACK_API ParticleSwarm {
 public:
  ParticleSwarm(PsoConfig config, ParameterSpace space);

  // Runs Algorithm 1 from the given initial configurations (N columns; N may
  // differ from config.particles). Velocities start at zero.
  PsoResult run(const Eigen::MatrixXd& initial, const BatchObjective& objective, std::mt19937_64& rng,
                const GenerationHook& hook = {}) const;

  // c1 of Algorithm 1 line 17 for rank in 1..n.
  static double c1(int rank, int n, double c);
  // Ranks (1 = lowest cost; ties by index) of `cost`.
  static std::vector<int> ranks(const Eigen::VectorXd& cost);

  // Algorithm 1 line 6 for the whole swarm: picks round(fraction * N)
  // particles (at least one) and re-draws one random parameter of each,
  // uniformly in [x - spread, x + spread] (the whole bounds where spread is
  // not set), then clamps. Returns the indices of the particles changed.
  std::vector<int> partial_randomization(Swarm& swarm, std::mt19937_64& rng) const;
  // Lines 16-21: rank-adaptive velocity and position update, with clamping.
  void update(Swarm& swarm, std::mt19937_64& rng) const;

  // Per-parameter half-width of the partial randomisation; empty = whole bounds.
  void set_randomization_spread(Eigen::VectorXd spread) { spread_ = std::move(spread); }

  const PsoConfig& config() const { return config_; }
  const ParameterSpace& space() const { return space_; }

 private:
  PsoConfig config_;
  ParameterSpace space_;
  Eigen::VectorXd spread_;
};

// Uniform random configurations inside a box.
GTRACK_API Eigen::MatrixXd uniform_swarm(const ParameterSpace& space, int n, std::mt19937_64& rng);

// The paper's initialisation from the previous frame's best: particle 0 is
// `previous` exactly; the others are `previous` plus a uniform perturbation in
// [-spread, spread] per parameter, except the joints: a share `fold_fraction`
// of the particles (Stimulus::fold_fraction) gets every joint increased by a
// uniform amount in [0, spread_joint], the rest decreased. `spread` has one
// entry per parameter of `space`.
GTRACK_API Eigen::MatrixXd biased_initial_swarm(const Eigen::VectorXd& previous, const Eigen::VectorXd& spread,
                                                double fold_fraction, int n, const ParameterSpace& space,
                                                std::mt19937_64& rng);

// A box with no periodic parameter, for plain functions.
GTRACK_API ParameterSpace box_space(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

// Minimises f over the box with Algorithm 1 from a uniform random swarm.
GTRACK_API PsoResult minimize(const std::function<double(const Eigen::VectorXd&)>& f, const ParameterSpace& space,
                              const PsoConfig& config);

}  // namespace gtrack
