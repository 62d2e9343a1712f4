// Our Algorithm 1 against pagmo2's generational PSO (pso_gen) at the same
// number of evaluations: textbook functions in 12-D, and the tracking cost of
// one synthetic frame started from a perturbed previous estimate.
// Prints a Markdown table (docs/pso_vs_pagmo.md has the numbers).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>
#include <pagmo/algorithms/pso_gen.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <vector>

#include "gtrack/cost.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/pso.hpp"
#include "gtrack/setup.hpp"

namespace {

using Fn = std::function<double(const Eigen::VectorXd&)>;

// pagmo wants a copyable problem; the function (and any renderer behind it) is shared.
struct Udp {
  std::shared_ptr<Fn> f;
  pagmo::vector_double lo, hi;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    return {(*f)(Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size())))};
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const { return {lo, hi}; }
};

double pagmo_run(const Fn& f, const gtrack::ParameterSpace& space, const Eigen::MatrixXd* initial, int n, int g,
                 unsigned seed) {
  Udp udp{std::make_shared<Fn>(f),
          pagmo::vector_double(space.lower.data(), space.lower.data() + space.dims()),
          pagmo::vector_double(space.upper.data(), space.upper.data() + space.dims())};
  pagmo::problem prob{udp};
  pagmo::population pop(prob, initial ? 0u : static_cast<pagmo::population::size_type>(n), seed);
  if (initial) {
    for (Eigen::Index i = 0; i < initial->cols(); ++i) {
      pop.push_back(pagmo::vector_double(initial->col(i).data(), initial->col(i).data() + initial->rows()));
    }
  }
  // pso_gen evaluates the initial population once, then n per generation:
  // g - 1 generations match our n * g evaluations.
  pagmo::pso_gen algo(static_cast<unsigned>(g - 1), 0.7298, 2.05, 2.05, 0.5, 5u, 2u, 4u, false, seed);
  pop = algo.evolve(pop);
  return pop.champion_f()[0];
}

double ours_run(const Fn& f, const gtrack::ParameterSpace& space, const Eigen::MatrixXd* initial, int n, int g,
                unsigned seed, const Eigen::VectorXd* spread = nullptr) {
  gtrack::PsoConfig c;
  c.particles = n;
  c.generations = g;
  c.seed = seed;
  std::mt19937_64 rng(seed);
  gtrack::ParticleSwarm pso(c, space);
  if (spread) pso.set_randomization_spread(*spread);
  const Eigen::MatrixXd init = initial ? *initial : gtrack::uniform_swarm(space, n, rng);
  return pso
      .run(init,
           [&](const Eigen::MatrixXd& x, Eigen::VectorXd& cost) {
             cost.resize(x.cols());
             for (Eigen::Index i = 0; i < x.cols(); ++i) cost[i] = f(x.col(i));
           },
           rng)
      .best_cost;
}

struct Stats {
  double mean = 0, median = 0, best = 0, worst = 0;
};
Stats stats(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  Stats s;
  for (double x : v) s.mean += x / v.size();
  s.median = v[v.size() / 2];
  s.best = v.front();
  s.worst = v.back();
  return s;
}

void row(const char* name, const char* who, const Stats& s, double ms) {
  std::printf("| %s | %s | %.3g | %.3g | %.3g | %.3g | %.1f |\n", name, who, s.mean, s.median, s.best, s.worst, ms);
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main() {
  const int runs = 10;
  std::printf("| function | optimizer | mean | median | best | worst | ms/run |\n|---|---|---|---|---|---|---|\n");
  struct Case {
    const char* name;
    double half;
    Fn f;
  };
  const std::vector<Case> cases = {
      {"sphere 12-D", 5.12, [](const Eigen::VectorXd& x) { return x.squaredNorm(); }},
      {"Rosenbrock 12-D", 2.048,
       [](const Eigen::VectorXd& x) {
         double s = 0;
         for (Eigen::Index i = 0; i + 1 < x.size(); ++i)
           s += 100 * std::pow(x[i + 1] - x[i] * x[i], 2) + std::pow(1 - x[i], 2);
         return s;
       }},
      {"Rastrigin 12-D", 5.12, [](const Eigen::VectorXd& x) {
         double s = 10.0 * x.size();
         for (Eigen::Index i = 0; i < x.size(); ++i) s += x[i] * x[i] - 10 * std::cos(2 * std::numbers::pi * x[i]);
         return s;
       }}};
  for (const auto& c : cases) {
    const auto space = gtrack::box_space(Eigen::VectorXd::Constant(12, -c.half), Eigen::VectorXd::Constant(12, c.half));
    for (int g : {25, 400}) {
      std::vector<double> a, b;
      auto t0 = std::chrono::steady_clock::now();
      for (int s = 1; s <= runs; ++s) a.push_back(ours_run(c.f, space, nullptr, 32, g, s));
      const double ta = ms_since(t0) / runs;
      t0 = std::chrono::steady_clock::now();
      for (int s = 1; s <= runs; ++s) b.push_back(pagmo_run(c.f, space, nullptr, 32, g, s));
      const double tb = ms_since(t0) / runs;
      char name[64];
      std::snprintf(name, sizeof name, "%s, N=32 G=%d", c.name, g);
      row(name, "gtrack (Algorithm 1)", stats(a), ta);
      row(name, "pagmo pso_gen", stats(b), tb);
    }
  }

  // The tracking cost: a hydrogel gripper rendered at a known pose is the
  // observation; both start from the same swarm around a perturbed estimate.
  gtrack::Setup setup = gtrack::load_setup(gtrack::ConfigTable::parse(R"(
[sensor]
plugin = "pinhole_microscope"
width = 1024
height = 1024
fx = 12800.0
[gripper]
plugin = "hydrogel_six_finger"
[render]
backend = "cpu"
)", "<bench>"), gtrack::SetupOptions{{}, false});
  const gtrack::EngineConfig config = gtrack::engine_config(setup);
  auto renderer = gtrack::make_renderer(config.render);
  renderer->set_model(setup.model());
  renderer->set_projection(setup.sensor->projection(), config.render.scale);
  Eigen::VectorXd truth(12);
  truth << 0.3, -0.2, 100.0, 12, -8, 30, 25, 25, 25, 25, 25, 25;
  renderer->set_observation(renderer->render_mask(truth));
  gtrack::CostEvaluator cost({renderer.get()}, *setup.gripper, nullptr, config.cost);
  const Fn tracking = [&](const Eigen::VectorXd& h) { return cost.evaluate_one(h).dice; };
  Eigen::VectorXd spread(12);
  spread << 0.2, 0.2, 0.2, 10, 10, 10, 10, 10, 10, 10, 10, 10;
  // The search box of one frame: the previous estimate's neighbourhood.
  gtrack::ParameterSpace local = config.space;
  local.lower = (truth - 3 * spread).cwiseMax(config.space.lower);
  local.upper = (truth + 3 * spread).cwiseMin(config.space.upper);
  local.periodic.assign(12, false);
  std::vector<double> a, b;
  double ta = 0, tb = 0;
  for (int s = 1; s <= runs; ++s) {
    std::mt19937_64 rng(100 + s);
    Eigen::VectorXd previous = truth;
    for (int d = 0; d < 12; ++d) previous[d] += spread[d] * std::uniform_real_distribution<double>(-1, 1)(rng);
    const Eigen::MatrixXd init = gtrack::biased_initial_swarm(previous, spread, 0.5, 32, local, rng);
    auto t0 = std::chrono::steady_clock::now();
    a.push_back(ours_run(tracking, local, &init, 32, 25, s, &spread));
    ta += ms_since(t0) / runs;
    t0 = std::chrono::steady_clock::now();
    b.push_back(pagmo_run(tracking, local, &init, 32, 25, s));
    tb += ms_since(t0) / runs;
  }
  row("tracking D, N=32 G=25", "gtrack (Algorithm 1)", stats(a), ta);
  row("tracking D, N=32 G=25", "pagmo pso_gen", stats(b), tb);
  return 0;
}
