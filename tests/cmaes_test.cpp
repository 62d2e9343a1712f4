// CMA-ES (the tracker's refinement) on textbook functions, against the
// paper's swarm on the same budget where the covariance is what matters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "gtrack/cmaes.hpp"
#include "gtrack/error.hpp"
#include "gtrack/pso.hpp"

namespace {

gtrack::ParameterSpace cube(int dims, double half) {
  return gtrack::box_space(Eigen::VectorXd::Constant(dims, -half), Eigen::VectorXd::Constant(dims, half));
}

// Scores every column with f, counting the batches.
gtrack::BatchObjective batch(const std::function<double(const Eigen::VectorXd&)>& f, int* calls = nullptr) {
  return [f, calls](const Eigen::MatrixXd& x, Eigen::VectorXd& c) {
    if (calls) ++*calls;
    c.resize(x.cols());
    for (Eigen::Index i = 0; i < x.cols(); ++i) c[i] = f(x.col(i));
  };
}

// An ellipsoid with condition number 1e3 whose axes are diagonals of the
// box (pairs of coordinates turned by 45 degrees): minimised along
// directions that mix parameters, like the tilt, depth and fold of a
// silhouette.
double rotated_ellipsoid(const Eigen::VectorXd& x) {
  const Eigen::Index n = x.size();
  double s = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index k = i - i % 2;  // the pair (k, k + 1)
    const double u = i % 2 == 0 ? (x[k] + x[k + 1]) / std::sqrt(2.0) : (x[k] - x[k + 1]) / std::sqrt(2.0);
    s += std::pow(1e3, static_cast<double>(i) / static_cast<double>(n - 1)) * u * u;
  }
  return s;
}

TEST(Cmaes, SphereConvergesFromAnOffsetMean) {
  std::mt19937_64 rng(1);
  gtrack::CmaesOptions o;
  o.generations = 150;
  const auto r = gtrack::cmaes_minimize(Eigen::VectorXd::Constant(12, 3.0), Eigen::VectorXd::Ones(12), cube(12, 5.12),
                                        o, batch([](const Eigen::VectorXd& x) { return x.squaredNorm(); }), rng);
  EXPECT_LT(r.best_cost, 1e-8);
  EXPECT_EQ(r.evaluations, 32u * 150u);
  ASSERT_EQ(r.best_cost_per_generation.size(), 150u);
  for (std::size_t g = 1; g < r.best_cost_per_generation.size(); ++g) {
    EXPECT_LE(r.best_cost_per_generation[g], r.best_cost_per_generation[g - 1]);
  }
}

// Costs that are not numbers (x0 > 0, where the search starts) rank last: it
// still finds the finite part and converges there.
TEST(Cmaes, CostsThatAreNotNumbersRankLast) {
  std::mt19937_64 rng(7);
  gtrack::CmaesOptions o;
  o.generations = 120;
  const auto f = [](const Eigen::VectorXd& x) {
    return x[0] > 0.0 ? std::numeric_limits<double>::quiet_NaN() : (x.array() + 1.0).square().sum();
  };
  const auto r = gtrack::cmaes_minimize(Eigen::VectorXd::Constant(6, 2.0), Eigen::VectorXd::Ones(6), cube(6, 5.12), o,
                                        batch(f), rng);
  ASSERT_TRUE(std::isfinite(r.best_cost));
  EXPECT_LT(r.best_cost, 1e-6);
  EXPECT_LE(r.best[0], 0.0);
  EXPECT_NEAR(r.best[0], -1.0, 1e-3);
}

TEST(Cmaes, LearnsARotatedValleyTheSwarmDoesNot) {
  const int dims = 12, generations = 200;
  const Eigen::VectorXd start = Eigen::VectorXd::Constant(dims, 1.0);
  std::mt19937_64 rng(2);
  gtrack::CmaesOptions o;
  o.generations = generations;
  const auto cma = gtrack::cmaes_minimize(start, Eigen::VectorXd::Ones(dims), cube(dims, 5), o,
                                          batch(rotated_ellipsoid), rng);
  // The paper's swarm, on the same number of evaluations, from a swarm drawn
  // within one unit of the same start.
  gtrack::PsoConfig pc;
  pc.generations = generations;
  gtrack::ParticleSwarm pso(pc, cube(dims, 5));
  std::mt19937_64 rng2(2);
  const Eigen::MatrixXd init =
      gtrack::biased_initial_swarm(start, Eigen::VectorXd::Ones(dims), 0.5, pc.particles, cube(dims, 5), rng2);
  const auto swarm = pso.run(init, batch(rotated_ellipsoid), rng2);
  EXPECT_EQ(cma.evaluations, swarm.evaluations);
  EXPECT_LT(cma.best_cost, 1e-8);
  EXPECT_LT(cma.best_cost, 1e-3 * swarm.best_cost) << "swarm " << swarm.best_cost;
  std::printf("rotated ellipsoid, %d evaluations: CMA-ES %.3g, swarm %.3g\n", static_cast<int>(cma.evaluations), cma.best_cost, swarm.best_cost);
}

TEST(Cmaes, EveryGenerationIsOneBatchInsideTheBox) {
  int calls = 0;
  const auto space = cube(4, 1.0);
  bool inside = true;
  const gtrack::BatchObjective f = [&](const Eigen::MatrixXd& x, Eigen::VectorXd& c) {
    ++calls;
    EXPECT_EQ(x.cols(), 10);
    for (Eigen::Index i = 0; i < x.cols(); ++i) inside = inside && space.contains(x.col(i));
    c = x.colwise().squaredNorm().transpose();
  };
  std::mt19937_64 rng(3);
  gtrack::CmaesOptions o;
  o.population = 10;
  o.generations = 7;
  o.step = 3.0;  // most samples land outside the box and are put back in
  const auto r = gtrack::cmaes_minimize(Eigen::VectorXd::Constant(4, 0.9), Eigen::VectorXd::Ones(4), space, o, f, rng);
  EXPECT_EQ(calls, 7);
  EXPECT_TRUE(inside);
  EXPECT_TRUE(space.contains(r.best));
}

TEST(Cmaes, SameSeedSameResult) {
  const auto run = [](std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    gtrack::CmaesOptions o;
    o.generations = 20;
    return gtrack::cmaes_minimize(Eigen::VectorXd::Constant(6, 2.0), Eigen::VectorXd::Ones(6), cube(6, 5), o,
                                  batch(rotated_ellipsoid), rng);
  };
  const auto a = run(7), b = run(7), c = run(8);
  EXPECT_EQ(a.best, b.best);
  EXPECT_EQ(a.best_cost, b.best_cost);
  EXPECT_NE(a.best, c.best);
}

TEST(Cmaes, RejectsMismatchedSizesAndEmptySettings) {
  std::mt19937_64 rng(1);
  const auto f = batch([](const Eigen::VectorXd& x) { return x.squaredNorm(); });
  gtrack::CmaesOptions o;
  EXPECT_THROW(gtrack::cmaes_minimize(Eigen::VectorXd::Zero(3), Eigen::VectorXd::Ones(2), cube(3, 1), o, f, rng),
               gtrack::Error);
  o.population = 2;
  EXPECT_THROW(gtrack::cmaes_minimize(Eigen::VectorXd::Zero(3), Eigen::VectorXd::Ones(3), cube(3, 1), o, f, rng),
               gtrack::Error);
}

}  // namespace
