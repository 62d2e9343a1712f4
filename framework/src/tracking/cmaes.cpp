#include "gtrack/cmaes.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "gtrack/error.hpp"

namespace gtrack {

PsoResult cmaes_minimize(const Eigen::VectorXd& mean, const Eigen::VectorXd& scale, const ParameterSpace& space,
                         const CmaesOptions& options, const BatchObjective& objective, std::mt19937_64& rng) {
  const int n = static_cast<int>(mean.size());
  if (n == 0 || scale.size() != n || space.dims() != n) {
    throw Error("cmaes_minimize: the mean, the scales and the parameter space differ in size");
  }
  if (options.population < 4 || options.generations < 1 || !(options.step > 0)) {
    throw Error("cmaes_minimize: needs a population of at least 4, a generation and a positive step");
  }
  // Strategy parameters (Hansen's tutorial, Table 1).
  const int lambda = options.population;
  const int mu = lambda / 2;
  Eigen::VectorXd w(mu);
  for (int i = 0; i < mu; ++i) w[i] = std::log(mu + 0.5) - std::log(i + 1.0);
  w /= w.sum();
  const double mueff = 1.0 / w.squaredNorm();
  const double dn = n;
  const double cc = (4 + mueff / dn) / (dn + 4 + 2 * mueff / dn);
  const double cs = (mueff + 2) / (dn + mueff + 5);
  const double c1 = 2 / ((dn + 1.3) * (dn + 1.3) + mueff);
  const double cmu = std::min(1 - c1, 2 * (mueff - 2 + 1 / mueff) / ((dn + 2) * (dn + 2) + mueff));
  const double damps = 1 + 2 * std::max(0.0, std::sqrt((mueff - 1) / (dn + 1)) - 1) + cs;
  const double chi_n = std::sqrt(dn) * (1 - 1 / (4 * dn) + 1 / (21 * dn * dn));

  // The search runs in u, with x = mean + scale .* u: every parameter in
  // units of its own scale, the distribution starting isotropic.
  Eigen::VectorXd m = Eigen::VectorXd::Zero(n), pc = m, ps = m;
  Eigen::MatrixXd C = Eigen::MatrixXd::Identity(n, n), B = C;
  Eigen::VectorXd D = Eigen::VectorXd::Ones(n);
  double sigma = options.step;
  std::normal_distribution<double> normal;

  PsoResult result;
  result.best_cost = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd y(n, lambda), x(n, lambda);
  Eigen::VectorXd cost, z(n);
  std::vector<int> order(lambda);
  for (int g = 0; g < options.generations; ++g) {
    for (int k = 0; k < lambda; ++k) {
      for (int d = 0; d < n; ++d) z[d] = normal(rng);
      y.col(k) = B * D.asDiagonal() * z;
      x.col(k) = mean + scale.cwiseProduct(m + sigma * y.col(k));
      space.clamp(x.col(k));
    }
    objective(x, cost);
    if (cost.size() != lambda) throw Error("cmaes_minimize: the objective returned the wrong number of costs");
    result.evaluations += static_cast<std::uint64_t>(lambda);
    // As in the swarm: a cost that is not a number (a plugin's term gone
    // wrong) ranks last instead of breaking the sort's order.
    for (int k = 0; k < lambda; ++k) {
      if (!std::isfinite(cost[k])) cost[k] = std::numeric_limits<double>::max();
    }
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return cost[a] < cost[b]; });
    if (cost[order[0]] < result.best_cost) {
      result.best_cost = cost[order[0]];
      result.best = x.col(order[0]);
    }
    result.best_cost_per_generation.push_back(result.best_cost);

    // Recombination, evolution paths, covariance and step size.
    Eigen::VectorXd yw = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < mu; ++i) yw += w[i] * y.col(order[i]);
    m += sigma * yw;
    const Eigen::MatrixXd c_inv_sqrt = B * D.cwiseInverse().asDiagonal() * B.transpose();
    ps = (1 - cs) * ps + std::sqrt(cs * (2 - cs) * mueff) * c_inv_sqrt * yw;
    const double ps_norm = ps.norm() / std::sqrt(1 - std::pow(1 - cs, 2.0 * (g + 1)));
    const double hsig = ps_norm / chi_n < 1.4 + 2 / (dn + 1) ? 1.0 : 0.0;
    pc = (1 - cc) * pc + hsig * std::sqrt(cc * (2 - cc) * mueff) * yw;
    Eigen::MatrixXd rank_mu = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < mu; ++i) rank_mu.noalias() += w[i] * y.col(order[i]) * y.col(order[i]).transpose();
    C = (1 - c1 - cmu) * C + c1 * (pc * pc.transpose() + (1 - hsig) * cc * (2 - cc) * C) + cmu * rank_mu;
    sigma *= std::exp((cs / damps) * (ps.norm() / chi_n - 1));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (C + C.transpose()));
    B = eigen.eigenvectors();
    D = eigen.eigenvalues().cwiseMax(1e-20).cwiseSqrt();
  }
  return result;
}

}  // namespace gtrack
