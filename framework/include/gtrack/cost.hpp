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
#include <span>
#include <string>
#include <utility>
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
  double temporal = 0;   // T (0 when no prediction is set)
  double total = 0;      // E
  // |P| and |O&P| in render pixels (summed over the views): P\O, what the
  // hypothesis shows where nothing was observed, is rendered - overlap.
  std::uint64_t rendered = 0;
  std::uint64_t overlap = 0;
  // Rendered pixels in the occlusion rim (0 when the rim is not used).
  std::uint64_t rim = 0;
  // D as the occlusion budget alone would score it (the rim's pixels taken
  // as hidden like the others): equal to `dice` without an allowance.
  double dice_without_rim = 1;
  // C: the fingers' joints' mean squared deviation from their mean, in
  // units of [cost] coherence_sigma_deg (0 for a gripper of one finger).
  double coherence = 0;
};

// D from counts. An empty observation and an empty hypothesis agree
// perfectly (0); an empty observation against a non-empty hypothesis is 1.
GTRACK_API double dice_distance(std::uint64_t intersection, std::uint64_t observed, std::uint64_t rendered);

// D with the rendered pixels outside O (P\O) weighted by outside_weight w in
// [0, 1]: D_w = 1 - 2|O&P| / (2|O&P| + |O\P| + w|P\O|), still in [0, 1].
// w = 1 is dice_distance. With w < 1 a hypothesis whose silhouette spills
// over where O is missing (an occluded part) is penalised less than one that
// leaves observed pixels uncovered.
//
// allowance a > 0, tolerance t: P\O pixels up to a + t are taken as hidden by
// an occluder and not counted (only the excess is, weighted by w), except
// that those between a and a + t count with tolerance_weight (times w); a = 0
// is no allowance at all (t is ignored). With a set to
// the area the observation lacks compared with the model's expected area,
// the true configuration of a partly hidden gripper scores about 0, as it
// would unoccluded, so shrinking or folding the hidden part away no longer
// pays, while a hypothesis that grows beyond the expected area still does.
//
// rim: how many of the P\O pixels lie in the rim, just outside O. They are
// never taken as hidden: the allowance and its tolerance apply to the other
// P\O pixels only. An occluder hides a part that continues the gripper, so
// the true configuration crosses the rim only along the occluder's edge,
// while a model placed loosely around the visible part spills along its
// whole outline.
GTRACK_API double weighted_dice_distance(std::uint64_t intersection, std::uint64_t observed, std::uint64_t rendered,
                                         double outside_weight, double allowance = 0, double tolerance = 0,
                                         double tolerance_weight = 0, std::uint64_t rim = 0);

// The temporal term T: mean over parameters of ((h_d - p_d) / sigma_d)^2, p
// the prediction; rz (index 5) differences are taken the short way when
// wrap_rz. Parameters with sigma_d <= 0 are skipped.
GTRACK_API double temporal_distance(const Eigen::Ref<const Eigen::VectorXd>& hypothesis,
                                    const Eigen::VectorXd& prediction, const Eigen::VectorXd& sigma, bool wrap_rz);

// The joint-coherence term C: mean over fingers of ((q_i - mean q) /
// sigma_deg)^2; 0 for fewer than two joints or sigma_deg <= 0.
GTRACK_API double joint_coherence(std::span<const double> joints, double sigma_deg);

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
  // How the gripper plugin is named in its errors (plugin_label()).
  void set_gripper_label(std::string label) { gripper_label_ = std::move(label); }
  // The temporal term (lambda_T * T): the predicted configuration and the
  // per-parameter scale. An empty prediction turns the term off.
  void set_prediction(Eigen::VectorXd prediction, Eigen::VectorXd sigma, bool wrap_rz) {
    prediction_ = std::move(prediction);
    sigma_ = std::move(sigma);
    wrap_rz_ = wrap_rz;
  }
  void clear_prediction() { prediction_.resize(0); }
  // Weight w of P\O in D (1 = plain D); clamped to [0, 1].
  void set_outside_weight(double w) { outside_weight_ = w < 0 ? 0 : (w > 1 ? 1 : w); }
  double outside_weight() const { return outside_weight_; }
  // P\O pixels (render pixels, per view) not counted in D: the area the
  // observation is believed to lack because of an occluder, and a tolerance
  // on it (see weighted_dice_distance). 0 = plain D.
  void set_outside_allowance(double pixels, double tolerance = 0) {
    outside_allowance_ = pixels > 0 ? pixels : 0;
    outside_tolerance_ = tolerance > 0 ? tolerance : 0;
  }
  double outside_allowance() const { return outside_allowance_; }
  double outside_tolerance() const { return outside_tolerance_; }
  // Whether the renderers' rim counts (PairCounts::rim) are used: the rim's
  // P\O pixels are never taken as hidden (see weighted_dice_distance).
  void set_use_rim(bool use) { use_rim_ = use; }
  const CostWeights& weights() const { return weights_; }
  std::uint64_t evaluations() const { return evaluations_; }

 private:
  std::vector<Renderer*> renderers_;
  const Gripper* gripper_;
  std::string gripper_label_ = "gripper plugin";
  const Stimulus* stimulus_;
  CostWeights weights_;
  std::vector<PairCounts> counts_;
  std::vector<CostTerms> scratch_;
  std::uint64_t evaluations_ = 0;
  Eigen::VectorXd prediction_, sigma_;
  bool wrap_rz_ = true;
  double outside_weight_ = 1.0;
  double outside_allowance_ = 0;
  double outside_tolerance_ = 0;
  bool use_rim_ = false;
};

}  // namespace gtrack
