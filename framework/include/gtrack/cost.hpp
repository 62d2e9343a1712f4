// The cost of a hypothesis, paper eq. (1): E = lambda_D D + lambda_K K + lambda_S S.
//
// D compares the rendered hypothesis P with the observation O from the two
// counts a Renderer returns: D = 1 - 2|O&P| / (|O&P| + |O|P|), with
// |O|P| = |O| + |P| - |O&P|. K is the gripper's kinematic penalty and S the
// stimulus penalty, both computed on the CPU while the renderer works. The
// evaluator scores a whole generation as one batch (submit, K and S, finish).
// The engine keeps "the sensor" a list: D is the mean over the renderers
// given, so several views of one gripper add up without a new cost.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "gtrack/engine_config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/gripper.hpp"
#include "gtrack/renderer.hpp"
#include "gtrack/stimulus.hpp"

namespace gtrack {

struct CostTerms {
  double dice = 1;       // D in [0, 1]
  double kinematic = 0;  // K
  double stimulus = 0;   // S
  double total = 0;      // E
};

// D from counts. An empty observation and an empty hypothesis agree
// perfectly (0); an empty observation against a non-empty hypothesis is 1.
GTRACK_API double dice_distance(std::uint64_t intersection, std::uint64_t observed, std::uint64_t rendered);

class GTRACK_API CostEvaluator {
 public:
  // stimulus may be null (no stimulus information: S = 0).
  CostEvaluator(std::vector<Renderer*> renderers, const Gripper& gripper, const Stimulus* stimulus,
                CostWeights weights);

  // Scores every column of `hypotheses` (one batch per renderer).
  void evaluate(const Eigen::MatrixXd& hypotheses, std::vector<CostTerms>& out);
  // Same, totals only (the PSO's objective).
  void evaluate(const Eigen::MatrixXd& hypotheses, Eigen::VectorXd& totals);
  CostTerms evaluate_one(const Eigen::VectorXd& hypothesis);

  void set_stimulus(const Stimulus* stimulus) { stimulus_ = stimulus; }
  const CostWeights& weights() const { return weights_; }
  std::uint64_t evaluations() const { return evaluations_; }

 private:
  std::vector<Renderer*> renderers_;
  const Gripper* gripper_;
  const Stimulus* stimulus_;
  CostWeights weights_;
  std::vector<PairCounts> counts_;
  std::vector<CostTerms> scratch_;
  std::uint64_t evaluations_ = 0;
};

}  // namespace gtrack
