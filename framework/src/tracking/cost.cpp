// Paper eq. (1) over a batch of hypotheses.
#include "gtrack/cost.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <span>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"

namespace gtrack {

double dice_distance(std::uint64_t intersection, std::uint64_t observed, std::uint64_t rendered) {
  // |O&P| + |O|P| = |O| + |P|, so D = 1 - 2|O&P| / (|O| + |P|).
  const std::uint64_t sum = observed + rendered;
  if (sum == 0) return 0.0;
  return 1.0 - 2.0 * static_cast<double>(intersection) / static_cast<double>(sum);
}

double weighted_dice_distance(std::uint64_t intersection, std::uint64_t observed, std::uint64_t rendered,
                              double outside_weight, double allowance, double tolerance, double tolerance_weight,
                              std::uint64_t rim) {
  if (intersection > rendered) intersection = rendered;
  const double w = outside_weight < 0 ? 0.0 : (outside_weight > 1 ? 1.0 : outside_weight);
  const double i = static_cast<double>(intersection);
  // |P\O| beyond the allowance (plus its tolerance): the part of the
  // hypothesis that cannot be hidden by the occluder. The part within the
  // tolerance counts with its own weight.
  double outside = static_cast<double>(rendered - intersection);
  if (allowance > 0) {
    // The rim's pixels are never hidden; the allowance covers the rest.
    const double near = std::min(outside, static_cast<double>(rim));
    const double rest = outside - near;
    const double t = std::max(0.0, tolerance);
    const double slack = std::clamp(rest - allowance, 0.0, t);
    outside = near + std::max(0.0, rest - allowance - t) + std::clamp(tolerance_weight, 0.0, 1.0) * slack;
  }
  const double denom = static_cast<double>(observed) + i + w * outside;  // 2|O&P| + |O\P| + w|P\O|
  if (denom <= 0) return rendered == 0 ? 0.0 : 1.0;
  const double d = 1.0 - 2.0 * i / denom;
  return d < 0 ? 0.0 : (d > 1 ? 1.0 : d);
}

double temporal_distance(const Eigen::Ref<const Eigen::VectorXd>& hypothesis, const Eigen::VectorXd& prediction,
                         const Eigen::VectorXd& sigma, bool wrap_rz) {
  const Eigen::Index n = std::min({hypothesis.size(), prediction.size(), sigma.size()});
  double sum = 0;
  int used = 0;
  for (Eigen::Index d = 0; d < n; ++d) {
    if (!(sigma[d] > 0)) continue;
    double diff = hypothesis[d] - prediction[d];
    if (d == 5 && wrap_rz) diff = std::remainder(diff, 360.0);
    const double z = diff / sigma[d];
    sum += z * z;
    ++used;
  }
  return used ? sum / used : 0.0;
}

double joint_coherence(std::span<const double> joints, double sigma_deg) {
  if (joints.size() < 2 || !(sigma_deg > 0)) return 0.0;
  double mean = 0;
  for (double q : joints) mean += q;
  mean /= static_cast<double>(joints.size());
  double sum = 0;
  for (double q : joints) sum += (q - mean) * (q - mean);
  return sum / (sigma_deg * sigma_deg) / static_cast<double>(joints.size());
}

CostEvaluator::CostEvaluator(std::vector<Renderer*> renderers, const Gripper& gripper, const Stimulus* stimulus,
                             CostWeights weights)
    : renderers_(std::move(renderers)), gripper_(&gripper), stimulus_(stimulus), weights_(weights) {
  if (renderers_.empty()) throw Error("cost: at least one renderer is needed");
}

void CostEvaluator::evaluate(const Eigen::MatrixXd& hypotheses, std::vector<CostTerms>& out) {
  const int n = static_cast<int>(hypotheses.cols());
  out.assign(n, CostTerms{});
  for (auto& t : out) t.dice = t.dice_without_rim = 0;
  // Every renderer started takes its batch's finish() whatever fails after
  // (a renderer's own error, a plugin's), so that it can take the next batch.
  size_t pending_from = 0, pending_to = 0;
  const auto collect_pending = [&] {
    for (; pending_from < pending_to; ++pending_from) {
      try {
        renderers_[pending_from]->finish(counts_);
      } catch (...) {
        // The first error is the one to report.
      }
    }
  };
  try {
    // Every renderer starts its batch first; K and S are computed while they work.
    for (; pending_to < renderers_.size(); ++pending_to) renderers_[pending_to]->submit(hypotheses);
    for (int i = 0; i < n; ++i) {
      const int joints = static_cast<int>(hypotheses.rows()) - kPoseDims;
      std::span<const double> q(hypotheses.col(i).data() + kPoseDims, joints);
      const auto joint_list = [&q] {
        std::string joints;
        for (double v : q) joints += (joints.empty() ? "" : ", ") + fmt::format("{:g}", v);
        return joints;
      };
      try {
        out[i].kinematic = gripper_->kinematic_penalty(q);
      } catch (const Error&) {
        throw;
      } catch (const std::exception& e) {
        throw PluginError(fmt::format("{}: kinematic_penalty() threw for the joints [{}] deg: {}", gripper_label_,
                                      joint_list(), e.what()));
      } catch (...) {
        throw PluginError(fmt::format("{}: kinematic_penalty() threw something that is not a std::exception for the "
                                      "joints [{}] deg",
                                      gripper_label_, joint_list()));
      }
      if (!std::isfinite(out[i].kinematic)) {
        throw PluginError(fmt::format("{}: kinematic_penalty() returned {} for the joints [{}] deg; expected a "
                                      "finite number (0 for a plausible configuration)",
                                      gripper_label_, out[i].kinematic, joint_list()));
      }
      out[i].stimulus = stimulus_ ? stimulus_->penalty(q) : 0.0;
      out[i].coherence = joint_coherence(q, weights_.coherence_sigma_deg);
      out[i].temporal = (prediction_.size() > 0 && weights_.temporal > 0)
                            ? temporal_distance(hypotheses.col(i), prediction_, sigma_, wrap_rz_)
                            : 0.0;
    }
  } catch (...) {
    collect_pending();
    throw;
  }
  for (; pending_from < pending_to; ++pending_from) {
    Renderer* r = renderers_[pending_from];
    try {
      r->finish(counts_);
    } catch (...) {
      ++pending_from;
      collect_pending();
      throw;
    }
    if (static_cast<int>(counts_.size()) != n) {
      const std::string said = "renderer '" + r->name() + "' returned " + std::to_string(counts_.size()) +
                               " counts for " + std::to_string(n) + " hypotheses";
      ++pending_from;
      collect_pending();  // (which overwrites counts_)
      throw Error(said);
    }
    const std::uint64_t observed = r->observation_count();
    for (int i = 0; i < n; ++i) {
      out[i].rendered += counts_[i].rendered;
      out[i].overlap += std::min(counts_[i].intersection, counts_[i].rendered);
      const std::uint64_t rim = use_rim_ ? counts_[i].rim : 0;
      out[i].rim += rim;
      const double budget_only =
          weighted_dice_distance(counts_[i].intersection, observed, counts_[i].rendered, outside_weight_,
                                 outside_allowance_, outside_tolerance_, weights_.occlusion_growth_weight);
      out[i].dice_without_rim += budget_only;
      out[i].dice += rim == 0 ? budget_only
                              : weighted_dice_distance(counts_[i].intersection, observed, counts_[i].rendered,
                                                       outside_weight_, outside_allowance_, outside_tolerance_,
                                                       weights_.occlusion_growth_weight, rim);
    }
  }
  const double views = static_cast<double>(renderers_.size());
  for (auto& t : out) {
    t.dice /= views;
    t.dice_without_rim /= views;
    t.total = weights_.dice * t.dice + weights_.kinematic * t.kinematic + weights_.stimulus * t.stimulus +
              weights_.temporal * t.temporal + weights_.coherence * t.coherence;
    // The plugins' terms are checked where they are made; this is the
    // engine's own (a temporal scale so small that any change is infinite).
    if (!std::isfinite(t.total)) {
      throw Error(fmt::format("cost: a hypothesis's cost is {} (D {}, K {}, S {}, T {}, C {}); expected a finite "
                              "number: check the [cost] weights and the [tracker] init_spread the temporal term "
                              "scales by",
                              t.total, t.dice, t.kinematic, t.stimulus, t.temporal, t.coherence));
    }
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
