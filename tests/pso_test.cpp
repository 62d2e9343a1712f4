// Algorithm 1 on textbook functions and its parts checked one by one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>

#include "gtrack/pso.hpp"

namespace {

using gtrack::ParticleSwarm;
using gtrack::PsoConfig;

double sphere(const Eigen::VectorXd& x) { return x.squaredNorm(); }
double rosenbrock(const Eigen::VectorXd& x) {
  double s = 0;
  for (Eigen::Index i = 0; i + 1 < x.size(); ++i) {
    s += 100 * std::pow(x[i + 1] - x[i] * x[i], 2) + std::pow(1 - x[i], 2);
  }
  return s;
}
double rastrigin(const Eigen::VectorXd& x) {
  double s = 10.0 * x.size();
  for (Eigen::Index i = 0; i < x.size(); ++i) s += x[i] * x[i] - 10 * std::cos(2 * std::numbers::pi * x[i]);
  return s;
}

gtrack::ParameterSpace cube(int dims, double half) {
  return gtrack::box_space(Eigen::VectorXd::Constant(dims, -half), Eigen::VectorXd::Constant(dims, half));
}

// Paper parameters except the budget: a whole optimisation from a random
// swarm needs more than the 25 generations a tracked frame gets.
PsoConfig textbook(std::uint64_t seed) {
  PsoConfig c;
  c.generations = 400;
  c.seed = seed;
  return c;
}

// Tolerances (12-D, N = 32, G = 400, seeds 1..3, documented in docs/tracker.md).
TEST(Pso, SphereConverges) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const auto r = gtrack::minimize(sphere, cube(12, 5.12), textbook(seed));
    std::printf("sphere seed %d: %.3g\n", static_cast<int>(seed), r.best_cost);
    EXPECT_LT(r.best_cost, 1e-8) << "seed " << seed;
    EXPECT_EQ(r.evaluations, 32u * 400u);
  }
}

TEST(Pso, RosenbrockGetsIntoTheValley) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const auto r = gtrack::minimize(rosenbrock, cube(12, 2.048), textbook(seed));
    std::printf("rosenbrock seed %d: %.3g\n", static_cast<int>(seed), r.best_cost);
    EXPECT_LT(r.best_cost, 11.0) << "seed " << seed;
  }
}

TEST(Pso, RastriginFindsALowBasin) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const auto r = gtrack::minimize(rastrigin, cube(12, 5.12), textbook(seed));
    std::printf("rastrigin seed %d: %.3g\n", static_cast<int>(seed), r.best_cost);
    EXPECT_LT(r.best_cost, 5.0) << "seed " << seed;
  }
}

TEST(Pso, SameSeedSameResultOtherSeedOtherPath) {
  const auto a = gtrack::minimize(rastrigin, cube(12, 5.12), textbook(7));
  const auto b = gtrack::minimize(rastrigin, cube(12, 5.12), textbook(7));
  const auto c = gtrack::minimize(rastrigin, cube(12, 5.12), textbook(8));
  EXPECT_EQ(a.best, b.best);
  EXPECT_EQ(a.best_cost_per_generation, b.best_cost_per_generation);
  EXPECT_NE(a.best, c.best);
}

TEST(Pso, RankCoefficientsFollowLine17) {
  const int n = 32;
  // rank 1 (best): c1 = C, c2 = 0; rank N (worst): c1 = 0, c2 = C.
  EXPECT_DOUBLE_EQ(ParticleSwarm::c1(1, n, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(ParticleSwarm::c1(n, n, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(ParticleSwarm::c1(16, n, 2.0), 2.0 / (31.0 * 31.0) * 16.0 * 16.0);
  for (int r = 1; r < n; ++r) EXPECT_GT(ParticleSwarm::c1(r, n, 1.0), ParticleSwarm::c1(r + 1, n, 1.0));
  Eigen::VectorXd cost(4);
  cost << 3.0, 1.0, 2.0, 0.5;
  EXPECT_EQ(ParticleSwarm::ranks(cost), (std::vector<int>{4, 2, 3, 1}));
}

// With w = 0 and C = 1, one update moves each particle by exactly
// c1 r1 (x^ - x) + c2 r2 (g^ - x): the best-ranked particle (c2 = 0) must
// not move toward g^ at all, the worst (c1 = 0) only toward g^.
TEST(Pso, UpdateUsesRankAdaptiveCoefficients) {
  PsoConfig c;
  c.inertia = 0;
  c.max_velocity_fraction = 0;
  ParticleSwarm pso(c, cube(2, 100));
  gtrack::Swarm s;
  s.x = Eigen::MatrixXd(2, 3);
  s.x << 0, 10, 20, 0, 10, 20;
  s.v = Eigen::MatrixXd::Zero(2, 3);
  s.best_x = s.x;  // own bests where they are: only the g^ term can move them
  s.cost = Eigen::Vector3d(1.0, 2.0, 3.0);
  s.best_cost = s.cost;
  s.g = Eigen::Vector2d(-50, -50);
  s.g_cost = 0;
  std::mt19937_64 rng(1);
  pso.update(s, rng);
  EXPECT_EQ(s.rank, (std::vector<int>{1, 2, 3}));
  EXPECT_DOUBLE_EQ(s.x(0, 0), 0.0);  // rank 1: c2 = 0
  EXPECT_DOUBLE_EQ(s.x(1, 0), 0.0);
  EXPECT_LT(s.x(0, 2), 20.0);  // rank N: pulled toward g^
  EXPECT_GE(s.x(0, 2), -50.0);
}

TEST(Pso, PartialRandomizationChangesOneParameterOfASubset) {
  PsoConfig c;
  c.particles = 32;
  c.randomize_fraction = 0.25;
  ParticleSwarm pso(c, cube(12, 5));
  std::mt19937_64 rng(3);
  gtrack::Swarm s;
  s.x = Eigen::MatrixXd::Zero(12, 32);
  const Eigen::MatrixXd before = s.x;
  const auto changed = pso.partial_randomization(s, rng);
  EXPECT_EQ(changed.size(), 8u);
  EXPECT_EQ(std::set<int>(changed.begin(), changed.end()).size(), 8u);
  for (int i = 0; i < 32; ++i) {
    const int diffs = static_cast<int>((s.x.col(i).array() != before.col(i).array()).count());
    const bool chosen = std::find(changed.begin(), changed.end(), i) != changed.end();
    EXPECT_EQ(diffs, chosen ? 1 : 0) << "particle " << i;
    EXPECT_TRUE(pso.space().contains(s.x.col(i)));
  }
}

TEST(Pso, PartialRandomizationHappensEveryKrGenerations) {
  PsoConfig c;
  c.generations = 25;
  c.randomize_every = 8;
  c.inertia = 0;
  c.c = 0;  // no movement: only the randomisation changes the swarm
  ParticleSwarm pso(c, cube(4, 5));
  std::mt19937_64 rng(5);
  const Eigen::MatrixXd init = Eigen::MatrixXd::Zero(4, 32);
  std::vector<int> changed_at;
  Eigen::MatrixXd prev = init;
  pso.run(init, [](const Eigen::MatrixXd& x, Eigen::VectorXd& cost) { cost = x.colwise().squaredNorm(); }, rng,
          [&](int k, const gtrack::Swarm& s) {
            if (s.x != prev) changed_at.push_back(k);
            prev = s.x;
          });
  EXPECT_EQ(changed_at, (std::vector<int>{8, 16, 24}));
}

TEST(Pso, EachGenerationIsOneBatchOfN) {
  PsoConfig c;
  ParticleSwarm pso(c, cube(12, 5));
  std::mt19937_64 rng(1);
  int calls = 0;
  const auto r = pso.run(gtrack::uniform_swarm(pso.space(), 32, rng),
                         [&](const Eigen::MatrixXd& x, Eigen::VectorXd& cost) {
                           ++calls;
                           EXPECT_EQ(x.cols(), 32);
                           cost = x.colwise().squaredNorm();
                         },
                         rng);
  EXPECT_EQ(calls, 25);
  EXPECT_EQ(r.evaluations, 800u);
  for (size_t k = 1; k < r.best_cost_per_generation.size(); ++k) {
    EXPECT_LE(r.best_cost_per_generation[k], r.best_cost_per_generation[k - 1]);
  }
}

TEST(Pso, BiasedInitialisationFollowsFoldFraction) {
  auto space = gtrack::ParameterSpace::make(6, Eigen::Vector3d::Constant(-10), Eigen::Vector3d::Constant(10),
                                            Eigen::Vector3d(-90, -90, -180), Eigen::Vector3d(90, 90, 180), -10, 90,
                                            true);
  Eigen::VectorXd prev(12);
  prev << 1, 2, 3, 10, 20, 30, 40, 40, 40, 40, 40, 40;
  Eigen::VectorXd spread(12);
  spread << 0.1, 0.1, 0.1, 5, 5, 5, 10, 10, 10, 10, 10, 10;
  for (double fraction : {0.75, 0.5, 0.25}) {
    std::mt19937_64 rng(11);
    const Eigen::MatrixXd x = gtrack::biased_initial_swarm(prev, spread, fraction, 33, space, rng);
    EXPECT_EQ(x.col(0), prev);  // one particle is the previous best exactly
    int up = 0, down = 0;
    for (int i = 1; i < 33; ++i) {
      const Eigen::ArrayXd dq = (x.col(i).tail(6) - prev.tail(6)).array();
      if ((dq >= 0).all()) ++up;
      else if ((dq <= 0).all()) ++down;
      else ADD_FAILURE() << "particle " << i << " has joints moved both ways";
      EXPECT_LE((x.col(i).head(6) - prev.head(6)).cwiseAbs().maxCoeff(), 5.0 + 1e-12);
      EXPECT_LE(dq.abs().maxCoeff(), 10.0 + 1e-12);
    }
    EXPECT_EQ(up, static_cast<int>(std::lround(fraction * 32))) << "fraction " << fraction;
    EXPECT_EQ(up + down, 32);
  }
}

TEST(Pso, PeriodicParameterWrapsAndMovesTheShortWay) {
  auto space = gtrack::ParameterSpace::make(0, Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1),
                                            Eigen::Vector3d(-90, -90, -180), Eigen::Vector3d(90, 90, 180), 0, 0, true);
  PsoConfig c;
  c.inertia = 0;
  c.max_velocity_fraction = 0;
  ParticleSwarm pso(c, space);
  gtrack::Swarm s;
  s.x = Eigen::MatrixXd::Zero(6, 2);
  s.x(5, 1) = 175;  // the worst particle, pulled only toward g^
  s.v = Eigen::MatrixXd::Zero(6, 2);
  s.best_x = s.x;
  s.cost = Eigen::Vector2d(0.0, 1.0);
  s.best_cost = s.cost;
  s.g = Eigen::VectorXd::Zero(6);
  s.g[5] = -175;
  s.g_cost = 0;
  std::mt19937_64 rng(2);
  pso.update(s, rng);
  // 175 -> toward -175 across +180: ends in [175, 180) or wraps to [-180, -175].
  const double rz = s.x(5, 1);
  EXPECT_TRUE(rz >= 175 || rz <= -175) << rz;
}

}  // namespace
