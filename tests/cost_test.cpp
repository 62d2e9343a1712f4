// Paper eq. (1): D from the renderer's counts, K and S from the plugins, weights.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "gtrack/cost.hpp"
#include "gtrack/error.hpp"

namespace {

// A renderer that returns prepared counts, to check the arithmetic alone.
class CountsRenderer final : public gtrack::Renderer {
 public:
  std::vector<gtrack::PairCounts> counts;
  std::uint64_t observed = 0;
  int submitted = 0, finished = 0;
  bool fail_submit = false, fail_finish = false;
  std::string name() const override { return "counts"; }
  void set_model(const gtrack::ArticulatedModel&) override {}
  void set_projection(const gtrack::Projection&, double) override {}
  gtrack::ImageSize render_size() const override { return {8, 8}; }
  void set_observation(const cv::Mat&) override {}
  void set_rim(const cv::Mat&) override {}
  std::uint64_t observation_count() const override { return observed; }
  void submit(const Eigen::MatrixXd& h) override {
    if (fail_submit) throw gtrack::Error("counts: no model");
    ++submitted;
    n_ = static_cast<int>(h.cols());
  }
  void finish(std::vector<gtrack::PairCounts>& out) override {
    ++finished;
    if (fail_finish) throw gtrack::Error("counts: lost the device");
    out.assign(counts.begin(), counts.begin() + std::min<std::ptrdiff_t>(n_, std::ssize(counts)));
  }
  cv::Mat render_mask(const Eigen::VectorXd&) override { return {}; }

 private:
  int n_ = 0;
};

class FixedGripper final : public gtrack::Gripper {
 public:
  FixedGripper() {
    gtrack::RadialGripperSpec s;
    s.name = "t";
    s.fingers = 2;
    s.palm_sides = 4;
    s.links = {{0.2, 0.1, 0.0}};
    model_ = gtrack::ArticulatedModel(gtrack::make_radial_gripper(s));
  }
  const gtrack::ArticulatedModel& model() const override { return model_; }
  double kinematic_penalty(std::span<const double> q) const override { return q[0] > 50 ? 0.5 : 0.0; }

 private:
  gtrack::ArticulatedModel model_;
};

class FixedStimulus final : public gtrack::Stimulus {
 public:
  void update(double, double) override {}
  gtrack::StimulusState state() const override { return {}; }
  double penalty(std::span<const double> q) const override { return q[1] < 10 ? 0.25 : 0.0; }
  double fold_fraction() const override { return 0.5; }
  double target_joint_deg(double c) const override { return c; }
};

// A plugin's error while the renderers work on a batch (a stimulus's
// unusable penalty) reaches the caller, and every batch is collected first:
// the gl renderer, left with a batch pending, had refused every later one.
TEST(Cost, APluginErrorDuringABatchLeavesNoBatchPending) {
  struct Failing final : gtrack::Stimulus {
    bool fail = true;
    void update(double, double) override {}
    gtrack::StimulusState state() const override { return {}; }
    double penalty(std::span<const double>) const override {
      if (fail) throw gtrack::PluginError("stimulus plugin 'failing': penalty() returned nan");
      return 0;
    }
    double fold_fraction() const override { return 0.5; }
    double target_joint_deg(double c) const override { return c; }
  };
  CountsRenderer a, b;
  a.counts = b.counts = {{10, 10}, {10, 10}};
  FixedGripper g;
  Failing s;
  gtrack::CostEvaluator eval({&a, &b}, g, &s, gtrack::CostWeights{});
  const Eigen::MatrixXd h = Eigen::MatrixXd::Zero(8, 2);
  std::vector<gtrack::CostTerms> t;
  EXPECT_THROW(eval.evaluate(h, t), gtrack::PluginError);
  EXPECT_EQ(a.finished, a.submitted);
  EXPECT_EQ(b.finished, b.submitted);
  s.fail = false;
  eval.evaluate(h, t);
  EXPECT_EQ(t.size(), 2u);
}

// A renderer's own error, in submit() or finish(), leaves no other view's
// batch pending: a view started before it is still collected, so that the
// next evaluation is taken once the cause is gone.
TEST(Cost, ARenderersErrorLeavesNoOtherViewsBatchPending) {
  FixedGripper g;
  const Eigen::MatrixXd h = Eigen::MatrixXd::Zero(8, 2);
  std::vector<gtrack::CostTerms> t;
  for (const bool in_finish : {false, true}) {
    SCOPED_TRACE(in_finish ? "finish() throws" : "submit() throws");
    CountsRenderer a, b, c;
    a.counts = b.counts = c.counts = {{10, 10}, {10, 10}};
    gtrack::CostEvaluator eval({&a, &b, &c}, g, nullptr, gtrack::CostWeights{});
    (in_finish ? a.fail_finish : b.fail_submit) = true;
    EXPECT_THROW(eval.evaluate(h, t), gtrack::Error);
    for (const CountsRenderer* r : {&a, &b, &c}) EXPECT_EQ(r->finished, r->submitted);
    a.fail_finish = b.fail_submit = false;
    eval.evaluate(h, t);
    EXPECT_EQ(t.size(), 2u);
    for (const CountsRenderer* r : {&a, &b, &c}) EXPECT_EQ(r->finished, r->submitted);
  }
  // A view that returns too few counts is named with its own count, not
  // that of a view collected after it.
  CountsRenderer a, b;
  a.counts = {{10, 10}};
  b.counts = {{10, 10}, {10, 10}};
  gtrack::CostEvaluator two({&a, &b}, g, nullptr, gtrack::CostWeights{});
  try {
    two.evaluate(Eigen::MatrixXd::Zero(8, 1), t);  // one hypothesis: both agree
    a.counts.clear();
    two.evaluate(h, t);
    ADD_FAILURE() << "a view's missing counts were taken";
  } catch (const gtrack::Error& e) {
    EXPECT_STREQ(e.what(), "renderer 'counts' returned 0 counts for 2 hypotheses");
  }
  EXPECT_EQ(b.finished, b.submitted);
}

// A gripper plugin's K that is no number is its error, named, not a cost
// of nan that no comparison would ever take or refuse.
TEST(Cost, AGripperPenaltyThatIsNoNumberIsThePluginsError) {
  struct NanGripper final : gtrack::Gripper {
    FixedGripper shape;
    const gtrack::ArticulatedModel& model() const override { return shape.model(); }
    double kinematic_penalty(std::span<const double> q) const override { return q[0] > 80 ? std::nan("") : 0.0; }
  };
  CountsRenderer r;
  r.counts = {{10, 10}, {10, 10}};
  NanGripper g;
  gtrack::CostEvaluator eval({&r}, g, nullptr, gtrack::CostWeights{});
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(8, 2);
  std::vector<gtrack::CostTerms> t;
  EXPECT_NO_THROW(eval.evaluate(h, t));
  h(6, 1) = 85;
  try {
    eval.evaluate(h, t);
    ADD_FAILURE() << "a penalty of nan was taken";
  } catch (const gtrack::PluginError& e) {
    EXPECT_STREQ(e.what(), "gripper plugin: kinematic_penalty() returned nan for the joints [85, 0] deg; "
                           "expected a finite number (0 for a plausible configuration)");
  }
  EXPECT_EQ(r.finished, r.submitted);
}

// A gripper plugin's own exception from kinematic_penalty() is its error,
// naming it as the tracker labels it, and the renderers' batch is
// collected all the same.
TEST(Cost, AGripperPenaltyThatThrowsIsThePluginsErrorNamingIt) {
  struct ThrowingGripper final : gtrack::Gripper {
    FixedGripper shape;
    const gtrack::ArticulatedModel& model() const override { return shape.model(); }
    double kinematic_penalty(std::span<const double> q) const override {
      if (q[1] > 80) throw std::out_of_range("joint 1 past the lookup table");
      return 0.0;
    }
  };
  CountsRenderer r;
  r.counts = {{10, 10}, {10, 10}};
  ThrowingGripper g;
  gtrack::CostEvaluator eval({&r}, g, nullptr, gtrack::CostWeights{});
  eval.set_gripper_label("gripper plugin 'lab_gripper' (/opt/lab/libgtrack_lab_gripper.so)");
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(8, 2);
  h(7, 0) = 90;
  std::vector<gtrack::CostTerms> t;
  try {
    eval.evaluate(h, t);
    ADD_FAILURE() << "the plugin's exception was not seen";
  } catch (const gtrack::PluginError& e) {
    EXPECT_STREQ(e.what(), "gripper plugin 'lab_gripper' (/opt/lab/libgtrack_lab_gripper.so): kinematic_penalty() "
                           "threw for the joints [0, 90] deg: joint 1 past the lookup table");
  }
  EXPECT_EQ(r.finished, r.submitted);
}

TEST(Cost, DiceDistanceFromCounts) {
  EXPECT_DOUBLE_EQ(gtrack::dice_distance(100, 100, 100), 0.0);  // identical
  EXPECT_DOUBLE_EQ(gtrack::dice_distance(0, 100, 50), 1.0);     // disjoint
  // |O&P| = 30, |O| = 60, |P| = 40: |O|P| = 70, D = 1 - 60/100.
  EXPECT_DOUBLE_EQ(gtrack::dice_distance(30, 60, 40), 1.0 - 60.0 / 100.0);
}

TEST(Cost, EmptyObservationDoesNotDivideByZero) {
  EXPECT_DOUBLE_EQ(gtrack::dice_distance(0, 0, 0), 0.0);
  EXPECT_DOUBLE_EQ(gtrack::dice_distance(0, 0, 25), 1.0);
  EXPECT_DOUBLE_EQ(gtrack::dice_distance(0, 25, 0), 1.0);
}

// A hypothesis that covers O exactly (D = 0), so that E is the other terms.
struct PerfectFit {
  CountsRenderer r;
  FixedGripper g;
  PerfectFit() {
    r.observed = 10;
    r.counts = {{10, 10}};
  }
};

TEST(Cost, WeightedSumOfTermsInOneBatch) {
  CountsRenderer r;
  r.observed = 60;
  r.counts = {{30, 40}, {60, 60}, {0, 0}};
  FixedGripper g;
  FixedStimulus s;
  gtrack::CostEvaluator eval({&r}, g, &s, gtrack::CostWeights{});
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(8, 3);
  h(6, 0) = 60;  // K = 0.5
  h(7, 0) = 5;   // S = 0.25
  h(7, 1) = 20;
  h(7, 2) = 20;
  std::vector<gtrack::CostTerms> t;
  eval.evaluate(h, t);
  EXPECT_EQ(r.submitted, 1);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_DOUBLE_EQ(t[0].dice, 0.4);
  EXPECT_DOUBLE_EQ(t[0].kinematic, 0.5);
  EXPECT_DOUBLE_EQ(t[0].stimulus, 0.25);
  // Joints (60, 5): C = ((27.5 / 10)^2 + (27.5 / 10)^2) / 2; (0, 20): C = 1.
  EXPECT_DOUBLE_EQ(t[0].coherence, 7.5625);
  // lambda_C is 0 by default (paper): C is reported, not added.
  EXPECT_DOUBLE_EQ(t[0].total, 2.0 * 0.4 + 0.15 * 0.5 + 1.0 * 0.25);
  EXPECT_DOUBLE_EQ(t[1].coherence, 1.0);
  EXPECT_DOUBLE_EQ(t[1].total, 0.0);
  EXPECT_DOUBLE_EQ(t[2].dice, 1.0);
  Eigen::VectorXd totals;
  eval.evaluate(h, totals);
  EXPECT_DOUBLE_EQ(totals[0], t[0].total);
  EXPECT_EQ(eval.evaluations(), 6u);
}

TEST(Cost, NoStimulusMeansNoS) {
  CountsRenderer r;
  r.observed = 10;
  r.counts = {{10, 10}};
  FixedGripper g;
  gtrack::CostEvaluator eval({&r}, g, nullptr, gtrack::CostWeights{});
  Eigen::VectorXd h = Eigen::VectorXd::Zero(8);
  EXPECT_DOUBLE_EQ(eval.evaluate_one(h).stimulus, 0.0);
  EXPECT_DOUBLE_EQ(eval.evaluate_one(h).total, 0.0);
}

TEST(Cost, SeveralViewsAverageD) {
  CountsRenderer a, b;
  a.observed = b.observed = 10;
  a.counts = {{10, 10}};
  b.counts = {{0, 10}};
  FixedGripper g;
  gtrack::CostEvaluator eval({&a, &b}, g, nullptr, gtrack::CostWeights{});
  EXPECT_DOUBLE_EQ(eval.evaluate_one(Eigen::VectorXd::Zero(8)).dice, 0.5);
}

TEST(Cost, OutsideWeightDiscountsOnlyRenderedPixelsOutsideO) {
  // w = 1 is the paper's D.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(30, 60, 40, 1.0), gtrack::dice_distance(30, 60, 40));
  // A hypothesis covering all of O (|O| = 50) and 50 more rendered pixels
  // (an occluded half): D = 1 - 100 / (100 + w 50).
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 100, 0.5), 1.0 - 100.0 / 125.0);
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 100, 0.0), 0.0);
  // Observed pixels left uncovered are not discounted.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(25, 50, 25, 0.5), gtrack::dice_distance(25, 50, 25));
  // Still in [0, 1], no division by zero, weight clamped.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(0, 0, 0, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(0, 0, 10, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(0, 10, 10, 0.3), 1.0);
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(30, 60, 40, 7.0), gtrack::dice_distance(30, 60, 40));
}

TEST(Cost, OccludedTruePoseBeatsShrunkenModelWithOutsideWeight) {
  // O = 50 visible pixels of a 100-pixel model: the true pose renders 100
  // (covering O), a shrunken hypothesis renders 60 (covering 45 of O).
  CountsRenderer r;
  r.observed = 50;
  r.counts = {{50, 100}, {45, 60}};
  FixedGripper g;
  gtrack::CostWeights w;
  w.temporal = 0;
  gtrack::CostEvaluator eval({&r}, g, nullptr, w);
  const Eigen::MatrixXd h = Eigen::MatrixXd::Zero(8, 2);
  std::vector<gtrack::CostTerms> t;
  eval.evaluate(h, t);
  EXPECT_GT(t[0].total, t[1].total);  // the paper's D prefers shrinking
  eval.set_outside_weight(0.1);       // a strong discount flips the order
  eval.evaluate(h, t);
  EXPECT_LT(t[0].total, t[1].total);
}

TEST(Cost, OutsideAllowanceTakesTheMissingAreaAsHidden) {
  // O = 50 visible pixels of a 100-pixel model. With the 50 missing pixels
  // allowed, the true pose (covering O, 100 rendered) scores 0, as it would
  // unoccluded.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 100, 1.0, 50), 0.0);
  // A shrunken hypothesis (60 rendered, 45 of them on O) gains nothing from
  // the allowance: it still leaves 5 observed pixels uncovered.
  const double shrunk = gtrack::weighted_dice_distance(45, 50, 60, 1.0, 50);
  EXPECT_DOUBLE_EQ(shrunk, 1.0 - 90.0 / 95.0);
  EXPECT_GT(shrunk, 0.0);
  // Growing beyond the allowance pays for the excess only: 130 outside, 80 counted.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 180, 1.0, 50), 1.0 - 100.0 / 180.0);
  // The tolerance widens the allowance; the weight applies to the excess.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 110, 1.0, 50, 10), 0.0);
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 180, 0.5, 50), 1.0 - 100.0 / 140.0);
  // No allowance: the paper's D.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(45, 50, 60, 1.0, 0), gtrack::dice_distance(45, 50, 60));
}

TEST(Cost, GrowthIntoTheToleranceIsWeighted) {
  // O = 50 pixels, allowance 50, tolerance 10. A hypothesis 8 pixels larger
  // than the allowance (58 outside) lies in the tolerance: free at weight 0,
  // 0.25 * 8 = 2 pixels counted at 0.25.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 108, 1.0, 50, 10, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 108, 1.0, 50, 10, 0.25), 1.0 - 100.0 / 102.0);
  // Beyond the tolerance the excess counts in full, the tolerance at its weight:
  // 75 outside = 50 allowed + 10 at 0.5 + 15.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 125, 1.0, 50, 10, 0.5), 1.0 - 100.0 / 120.0);
  // Within the allowance itself nothing is counted, whatever the weight.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 100, 1.0, 50, 10, 1.0), 0.0);
  // So with a weight, growing from the allowed size costs, and the true size does not.
  EXPECT_LT(gtrack::weighted_dice_distance(50, 50, 100, 1.0, 50, 10, 0.1),
            gtrack::weighted_dice_distance(50, 50, 105, 1.0, 50, 10, 0.1));
}

TEST(Cost, OccludedTruePoseBeatsShrunkenModelWithOutsideAllowance) {
  CountsRenderer r;
  r.observed = 50;
  r.counts = {{50, 100}, {45, 60}};
  FixedGripper g;
  gtrack::CostEvaluator eval({&r}, g, nullptr, gtrack::CostWeights{});
  const Eigen::MatrixXd h = Eigen::MatrixXd::Zero(8, 2);
  std::vector<gtrack::CostTerms> t;
  eval.evaluate(h, t);
  EXPECT_GT(t[0].total, t[1].total);  // the paper's D prefers shrinking
  eval.set_outside_allowance(50);
  EXPECT_DOUBLE_EQ(eval.outside_allowance(), 50.0);
  eval.evaluate(h, t);
  EXPECT_LT(t[0].total, t[1].total);
  eval.set_outside_allowance(-3);  // clamped
  EXPECT_DOUBLE_EQ(eval.outside_allowance(), 0.0);
}

TEST(Cost, RimPixelsAreNeverTakenAsHidden) {
  // O = 50 pixels of a 100-pixel model, allowance 50. The true pose spills
  // 50 pixels, 5 of them in the rim (along the occluder's edge): 45 are
  // allowed, the 5 count.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 100, 1.0, 50, 0, 0, 5), 1.0 - 100.0 / 105.0);
  // A model placed loosely around O spills the same 50 pixels, 30 of them
  // along the visible outline: it pays for those 30.
  const double loose = gtrack::weighted_dice_distance(50, 50, 100, 1.0, 50, 0, 0, 30);
  EXPECT_DOUBLE_EQ(loose, 1.0 - 100.0 / 130.0);
  EXPECT_GT(loose, gtrack::weighted_dice_distance(50, 50, 100, 1.0, 50, 0, 0, 5));
  // The allowance and its tolerance cover the other P\O pixels: 70 outside,
  // 10 in the rim, 60 others = 50 allowed + 10 in the tolerance at 0.5.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 120, 1.0, 50, 10, 0.5, 10), 1.0 - 100.0 / 115.0);
  // A rim count above |P\O| counts no more than P\O.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(50, 50, 100, 1.0, 50, 0, 0, 500), gtrack::dice_distance(50, 50, 100));
  // Without an allowance every P\O pixel counts anyway: the rim changes nothing.
  EXPECT_DOUBLE_EQ(gtrack::weighted_dice_distance(45, 50, 60, 1.0, 0, 0, 0, 7), gtrack::dice_distance(45, 50, 60));
}

TEST(Cost, EvaluatorUsesTheRimCountsOnlyWhenAsked) {
  CountsRenderer r;
  r.observed = 50;
  gtrack::PairCounts tight{50, 100, 5}, loose{50, 100, 30};
  r.counts = {tight, loose};
  FixedGripper g;
  gtrack::CostEvaluator eval({&r}, g, nullptr, gtrack::CostWeights{});
  eval.set_outside_allowance(50);
  const Eigen::MatrixXd h = Eigen::MatrixXd::Zero(8, 2);
  std::vector<gtrack::CostTerms> t;
  eval.evaluate(h, t);
  EXPECT_DOUBLE_EQ(t[0].dice, 0.0);  // the budget alone cannot tell them apart
  EXPECT_DOUBLE_EQ(t[1].dice, 0.0);
  eval.set_use_rim(true);
  eval.evaluate(h, t);
  EXPECT_DOUBLE_EQ(t[0].dice, 1.0 - 100.0 / 105.0);
  EXPECT_DOUBLE_EQ(t[1].dice, 1.0 - 100.0 / 130.0);
  EXPECT_LT(t[0].total, t[1].total);
  // The rim pixels are reported, and D without them is the budget's alone.
  EXPECT_EQ(t[0].rim, 5u);
  EXPECT_EQ(t[1].rim, 30u);
  EXPECT_DOUBLE_EQ(t[0].dice_without_rim, 0.0);
  EXPECT_DOUBLE_EQ(t[1].dice_without_rim, 0.0);
}

TEST(Cost, TemporalTermIsMahalanobisToThePrediction) {
  Eigen::VectorXd p = Eigen::VectorXd::Zero(8), sigma = Eigen::VectorXd::Ones(8);
  sigma[2] = 0;  // skipped
  Eigen::VectorXd h = p;
  EXPECT_DOUBLE_EQ(gtrack::temporal_distance(h, p, sigma, true), 0.0);
  h[0] = 2;    // (2/1)^2
  h[2] = 100;  // skipped
  EXPECT_DOUBLE_EQ(gtrack::temporal_distance(h, p, sigma, true), 4.0 / 7.0);
  // rz the short way: 179 vs -179 is 2 degrees apart.
  h.setZero();
  p[5] = -179;
  h[5] = 179;
  sigma[5] = 2;
  EXPECT_NEAR(gtrack::temporal_distance(h, p, sigma, true), 1.0 / 7.0, 1e-12);
  EXPECT_GT(gtrack::temporal_distance(h, p, sigma, false), 1000.0 / 7.0);

  // In the evaluator: lambda_T * T is added; no prediction, no term.
  PerfectFit fit;
  gtrack::CostWeights w;
  w.temporal = 0.5;
  gtrack::CostEvaluator eval({&fit.r}, fit.g, nullptr, w);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(8);
  x[0] = 1;
  EXPECT_DOUBLE_EQ(eval.evaluate_one(x).total, 0.0);
  eval.set_prediction(Eigen::VectorXd::Zero(8), Eigen::VectorXd::Ones(8), true);
  const gtrack::CostTerms c = eval.evaluate_one(x);
  EXPECT_DOUBLE_EQ(c.temporal, 1.0 / 8.0);
  EXPECT_DOUBLE_EQ(c.total, 0.5 / 8.0);
  eval.clear_prediction();
  EXPECT_DOUBLE_EQ(eval.evaluate_one(x).total, 0.0);
}

TEST(Cost, CoherenceTermIsTheFingersSpreadAboutTheirMean) {
  const std::vector<double> alike = {40, 40, 40, 40};
  EXPECT_DOUBLE_EQ(gtrack::joint_coherence(alike, 10), 0.0);
  // Mean 40: deviations -20, 0, 0, 20 -> ((2)^2 + (2)^2) / 4 = 2.
  const std::vector<double> apart = {20, 40, 40, 60};
  EXPECT_DOUBLE_EQ(gtrack::joint_coherence(apart, 10), 2.0);
  EXPECT_DOUBLE_EQ(gtrack::joint_coherence(apart, 20), 0.5);
  // One finger, or no scale: no term.
  EXPECT_DOUBLE_EQ(gtrack::joint_coherence(std::vector<double>{70}, 10), 0.0);
  EXPECT_DOUBLE_EQ(gtrack::joint_coherence(apart, 0), 0.0);

  // In the evaluator: lambda_C * C is added, and lambda_C = 0 leaves it out.
  PerfectFit fit;
  gtrack::CostWeights w;
  w.coherence = 0.5;
  w.coherence_sigma_deg = 5;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(8);
  x[6] = 10;  // joints (10, 20): mean 15, C = (1 + 1) / 2 = 1
  x[7] = 20;
  const gtrack::CostTerms c = gtrack::CostEvaluator({&fit.r}, fit.g, nullptr, w).evaluate_one(x);
  EXPECT_DOUBLE_EQ(c.coherence, 1.0);
  EXPECT_DOUBLE_EQ(c.total, 0.5);
  w.coherence = 0;
  EXPECT_DOUBLE_EQ(gtrack::CostEvaluator({&fit.r}, fit.g, nullptr, w).evaluate_one(x).total, 0.0);
}

}  // namespace
