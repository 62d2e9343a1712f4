// CMA-ES, the covariance matrix adaptation evolution strategy
// ((mu/mu_w, lambda)-CMA-ES with rank-one and rank-mu updates and
// cumulative step-size adaptation; N. Hansen, "The CMA Evolution Strategy:
// A Tutorial", arXiv:1604.00772, the default parameters of its Table 1).
//
// The tracker's refinement uses it (docs/tracker.md, "The refinement"): after
// the swarm, the result is refined by a search that learns which parameters
// move together. Tilt, depth and fold trade off against each other in a
// silhouette, so the lower cost is along a diagonal of the parameter box;
// the covariance finds that diagonal within a few generations, where a swarm
// whose moves are drawn parameter by parameter keeps stepping off it.
//
// Each generation's lambda samples are evaluated as ONE batch (one render
// call on the gl backend). Samples are drawn around the mean in units of
// `scale` (one value per parameter) and put inside the box (periodic
// parameters wrap) before they are scored; the distribution itself is not
// bounded. Everything random comes from the caller's std::mt19937_64.
//
// (pagmo2's cmaes evaluates one vector at a time in the 2.18 that Debian 12
// ships; batch evaluation came with 2.19.)
#pragma once

#include <Eigen/Core>
#include <random>

#include "gtrack/export.hpp"
#include "gtrack/parameter_space.hpp"
#include "gtrack/pso.hpp"

namespace gtrack {

struct CmaesOptions {
  int population = 32;   // lambda, samples per generation (>= 4)
  int generations = 25;  // generations, each one batch
  double step = 1.0;     // initial step size sigma, in units of `scale`
};

// Minimises `objective` from `mean`; the first generation's samples have
// standard deviation step * scale[d] in parameter d. Returns the lowest-cost
// sample ever scored (not the final mean), its cost, the number of
// evaluations and the best cost after each generation.
GTRACK_API PsoResult cmaes_minimize(const Eigen::VectorXd& mean, const Eigen::VectorXd& scale,
                                    const ParameterSpace& space, const CmaesOptions& options,
                                    const BatchObjective& objective, std::mt19937_64& rng);

}  // namespace gtrack
