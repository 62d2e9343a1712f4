// Paper eq. (1) over a batch of hypotheses.
#include "gtrack/cost.hpp"

#include <span>

#include "gtrack/error.hpp"

namespace gtrack {

double dice_distance(std::uint64_t intersection, std::uint64_t observed, std::uint64_t rendered) {
  // |O&P| + |O|P| = |O| + |P|, so D = 1 - 2|O&P| / (|O| + |P|).
  const std::uint64_t sum = observed + rendered;
  if (sum == 0) return 0.0;
  return 1.0 - 2.0 * static_cast<double>(intersection) / static_cast<double>(sum);
}

CostEvaluator::CostEvaluator(std::vector<Renderer*> renderers, const Gripper& gripper, const Stimulus* stimulus,
                             CostWeights weights)
    : renderers_(std::move(renderers)), gripper_(&gripper), stimulus_(stimulus), weights_(weights) {
  if (renderers_.empty()) throw Error("cost: at least one renderer is needed");
}

void CostEvaluator::evaluate(const Eigen::MatrixXd& hypotheses, std::vector<CostTerms>& out) {
  const int n = static_cast<int>(hypotheses.cols());
  out.assign(n, CostTerms{});
  for (auto& t : out) t.dice = 0;
  // Every renderer starts its batch first; K and S are computed while they work.
  for (Renderer* r : renderers_) r->submit(hypotheses);
  for (int i = 0; i < n; ++i) {
    const int joints = static_cast<int>(hypotheses.rows()) - kPoseDims;
    std::span<const double> q(hypotheses.col(i).data() + kPoseDims, joints);
    out[i].kinematic = gripper_->kinematic_penalty(q);
    out[i].stimulus = stimulus_ ? stimulus_->penalty(q) : 0.0;
  }
  for (Renderer* r : renderers_) {
    r->finish(counts_);
    if (static_cast<int>(counts_.size()) != n) {
      throw Error("renderer '" + r->name() + "' returned " + std::to_string(counts_.size()) + " counts for " +
                  std::to_string(n) + " hypotheses");
    }
    const std::uint64_t observed = r->observation_count();
    for (int i = 0; i < n; ++i) {
      out[i].dice += dice_distance(counts_[i].intersection, observed, counts_[i].rendered);
    }
  }
  const double views = static_cast<double>(renderers_.size());
  for (auto& t : out) {
    t.dice /= views;
    t.total = weights_.dice * t.dice + weights_.kinematic * t.kinematic + weights_.stimulus * t.stimulus;
  }
  evaluations_ += n;
}

void CostEvaluator::evaluate(const Eigen::MatrixXd& hypotheses, Eigen::VectorXd& totals) {
  evaluate(hypotheses, scratch_);
  totals.resize(hypotheses.cols());
  for (size_t i = 0; i < scratch_.size(); ++i) totals[static_cast<Eigen::Index>(i)] = scratch_[i].total;
}

CostTerms CostEvaluator::evaluate_one(const Eigen::VectorXd& hypothesis) {
  std::vector<CostTerms> t;
  evaluate(Eigen::MatrixXd(hypothesis), t);
  return t.front();
}

}  // namespace gtrack
