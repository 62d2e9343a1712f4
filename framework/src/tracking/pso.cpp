// Algorithm 1 of the paper; see pso.hpp for the conventions.
#include "gtrack/pso.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "gtrack/error.hpp"

namespace gtrack {

namespace {

// Short-way difference for periodic parameters, so that a particle at 179 deg
// and a best at -179 deg are 2 deg apart, not 358.
double difference(const ParameterSpace& space, int d, double to, double from) {
  double diff = to - from;
  if (space.periodic[d]) {
    const double span = space.upper[d] - space.lower[d];
    diff = std::remainder(diff, span);
  }
  return diff;
}

void evaluate(const BatchObjective& objective, const Eigen::MatrixXd& x, Eigen::VectorXd& cost) {
  objective(x, cost);
  if (cost.size() != x.cols()) throw Error("PSO objective returned " + std::to_string(cost.size()) +
                                           " costs for " + std::to_string(x.cols()) + " hypotheses");
  // A NaN would never compare as better and would freeze the particle's
  // best; treat it as the worst possible score instead.
  for (Eigen::Index i = 0; i < cost.size(); ++i) {
    if (!std::isfinite(cost[i])) cost[i] = std::numeric_limits<double>::max();
  }
}

}  // namespace

ParticleSwarm::ParticleSwarm(PsoConfig config, ParameterSpace space)
    : config_(std::move(config)), space_(std::move(space)) {
  if (config_.particles < 2) throw Error("PSO needs at least 2 particles");
  if (config_.generations < 1) throw Error("PSO needs at least 1 generation");
}

double ParticleSwarm::c1(int rank, int n, double c) {
  if (n < 2) return 0;
  const double d = static_cast<double>(rank - n);
  return c / (static_cast<double>(n - 1) * (n - 1)) * d * d;
}

std::vector<int> ParticleSwarm::ranks(const Eigen::VectorXd& cost) {
  const int n = static_cast<int>(cost.size());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return cost[a] < cost[b]; });
  std::vector<int> rank(n);
  for (int r = 0; r < n; ++r) rank[order[r]] = r + 1;
  return rank;
}

std::vector<int> ParticleSwarm::partial_randomization(Swarm& swarm, std::mt19937_64& rng) const {
  const int n = swarm.size();
  const int dims = static_cast<int>(swarm.x.rows());
  const int count =
      std::clamp(static_cast<int>(std::lround(config_.randomize_fraction * n)), 1, n);
  std::vector<int> chosen(n);
  std::iota(chosen.begin(), chosen.end(), 0);
  // A partial Fisher-Yates shuffle picks `count` distinct particles.
  for (int i = 0; i < count; ++i) {
    std::uniform_int_distribution<int> pick(i, n - 1);
    std::swap(chosen[i], chosen[pick(rng)]);
  }
  chosen.resize(count);
  std::uniform_int_distribution<int> which(0, dims - 1);
  for (int i : chosen) {
    const int d = which(rng);
    double lo = space_.lower[d], hi = space_.upper[d];
    if (spread_.size() == dims && spread_[d] > 0) {
      lo = swarm.x(d, i) - spread_[d];
      hi = swarm.x(d, i) + spread_[d];
    }
    swarm.x(d, i) = std::uniform_real_distribution<double>(lo, hi)(rng);
    space_.clamp(swarm.x.col(i));
  }
  return chosen;
}

void ParticleSwarm::update(Swarm& swarm, std::mt19937_64& rng) const {
  const int n = swarm.size();
  const int dims = static_cast<int>(swarm.x.rows());
  swarm.rank = ranks(swarm.cost);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    const double c1 = ParticleSwarm::c1(swarm.rank[i], n, config_.c);
    const double c2 = config_.c - c1;
    for (int d = 0; d < dims; ++d) {
      const double r1 = unit(rng), r2 = unit(rng);
      double v = config_.inertia * swarm.v(d, i) +
                 c1 * r1 * difference(space_, d, swarm.best_x(d, i), swarm.x(d, i)) +
                 c2 * r2 * difference(space_, d, swarm.g[d], swarm.x(d, i));
      if (config_.max_velocity_fraction > 0) {
        const double vmax = config_.max_velocity_fraction * (space_.upper[d] - space_.lower[d]);
        v = std::clamp(v, -vmax, vmax);
      }
      swarm.v(d, i) = v;
      swarm.x(d, i) += v;
    }
    space_.clamp(swarm.x.col(i));
  }
}

PsoResult ParticleSwarm::run(const Eigen::MatrixXd& initial, const BatchObjective& objective,
                             std::mt19937_64& rng, const GenerationHook& hook) const {
  if (initial.rows() != space_.dims()) {
    throw Error("PSO: initial swarm has " + std::to_string(initial.rows()) + " parameters, space has " +
                std::to_string(space_.dims()));
  }
  if (initial.cols() < 1) throw Error("PSO: empty initial swarm");
  Swarm s;
  s.x = initial;
  for (int i = 0; i < s.size(); ++i) space_.clamp(s.x.col(i));
  s.v = Eigen::MatrixXd::Zero(s.x.rows(), s.x.cols());
  s.best_x = s.x;
  s.best_cost = Eigen::VectorXd::Constant(s.size(), std::numeric_limits<double>::infinity());
  s.g = s.x.col(0);
  s.g_cost = std::numeric_limits<double>::infinity();

  PsoResult result;
  result.best_cost_per_generation.reserve(config_.generations);
  for (int k = 1; k <= config_.generations; ++k) {
    if (config_.randomize_every > 0 && k % config_.randomize_every == 0) partial_randomization(s, rng);
    evaluate(objective, s.x, s.cost);
    result.evaluations += s.size();
    for (int i = 0; i < s.size(); ++i) {
      if (s.cost[i] < s.best_cost[i]) {
        s.best_cost[i] = s.cost[i];
        s.best_x.col(i) = s.x.col(i);
      }
      if (s.best_cost[i] < s.g_cost) {
        s.g_cost = s.best_cost[i];
        s.g = s.best_x.col(i);
      }
    }
    result.best_cost_per_generation.push_back(s.g_cost);
    // The last generation's move would never be evaluated: skip it so the
    // random stream and the swarm end where the result was found.
    if (k < config_.generations) update(s, rng);
    if (hook) hook(k, s);
  }
  result.best = s.g;
  result.best_cost = s.g_cost;
  return result;
}

Eigen::MatrixXd uniform_swarm(const ParameterSpace& space, int n, std::mt19937_64& rng) {
  Eigen::MatrixXd x(space.dims(), n);
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < space.dims(); ++d) {
      x(d, i) = std::uniform_real_distribution<double>(space.lower[d], space.upper[d])(rng);
    }
  }
  return x;
}

Eigen::MatrixXd biased_initial_swarm(const Eigen::VectorXd& previous, const Eigen::VectorXd& spread,
                                     double fold_fraction, int n, const ParameterSpace& space,
                                     std::mt19937_64& rng) {
  const int dims = space.dims();
  if (previous.size() != dims || spread.size() != dims) {
    throw Error("biased_initial_swarm: vector sizes do not match the parameter space");
  }
  Eigen::MatrixXd x(dims, n);
  x.col(0) = previous;
  // Which particles fold is decided by count, not by coin flips, so that the
  // share is exactly the stimulus's fraction of the perturbed particles.
  const int others = n - 1;
  const int folding = static_cast<int>(std::lround(std::clamp(fold_fraction, 0.0, 1.0) * others));
  std::vector<int> order(others);
  std::iota(order.begin(), order.end(), 1);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<bool> folds(n, false);
  for (int i = 0; i < folding; ++i) folds[order[i]] = true;
  std::uniform_real_distribution<double> sym(-1.0, 1.0), pos(0.0, 1.0);
  for (int i = 1; i < n; ++i) {
    for (int d = 0; d < kPoseDims && d < dims; ++d) x(d, i) = previous[d] + spread[d] * sym(rng);
    for (int d = kPoseDims; d < dims; ++d) {
      const double step = spread[d] * pos(rng);
      x(d, i) = previous[d] + (folds[i] ? step : -step);
    }
    space.clamp(x.col(i));
  }
  return x;
}

ParameterSpace box_space(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  ParameterSpace s;
  for (Eigen::Index d = 0; d < lower.size(); ++d) s.names.push_back("p" + std::to_string(d + 1));
  s.lower = lower;
  s.upper = upper;
  s.periodic.assign(lower.size(), false);
  return s;
}

PsoResult minimize(const std::function<double(const Eigen::VectorXd&)>& f, const ParameterSpace& space,
                   const PsoConfig& config) {
  std::mt19937_64 rng(config.seed);
  ParticleSwarm pso(config, space);
  const Eigen::MatrixXd initial = uniform_swarm(space, config.particles, rng);
  return pso.run(
      initial,
      [&](const Eigen::MatrixXd& x, Eigen::VectorXd& c) {
        c.resize(x.cols());
        for (Eigen::Index i = 0; i < x.cols(); ++i) c[i] = f(x.col(i));
      },
      rng);
}

}  // namespace gtrack
