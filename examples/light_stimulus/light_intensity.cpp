// light_intensity: a gripper whose hinges fold under light (an example of a
// lab-specific stimulus plugin, built out of tree).
//
// Photo-responsive hinges (e.g. a gold-nanorod-doped hydrogel) fold while the
// irradiance is above `fold_above_mW_cm2` and relax below
// `unfold_below_mW_cm2`. The log is the usual stimulus CSV with the
// irradiance as its value column. S(H) follows the temperature plugin's
// rule: joints outside the band the light allows are infeasible. The hinges
// take time to follow the light, so for `settle_s` seconds after the light
// leaves the band the whole range stays feasible. The swarm
// bias is simpler: while the light is in the band and rising (by more than
// `trend_threshold_mW_cm2_per_s`), most particles start more folded.
#include <algorithm>
#include <cmath>
#include <gtrack/error.hpp>
#include <gtrack/plugin.hpp>

namespace {

class LightIntensity final : public gtrack::Stimulus {
 public:
  explicit LightIntensity(const gtrack::ConfigTable& t) {
    using gtrack::Range;
    unfold_below_ = t.number_or("unfold_below_mW_cm2", 20.0, Range::non_negative());
    fold_above_ = t.number_or("fold_above_mW_cm2", 60.0, Range::non_negative());
    unfolded_ = t.number_or("unfolded_deg", 0.0);
    folded_ = t.number_or("folded_deg", 50.0);
    tolerance_ = t.number_or("tolerance_deg", 8.0, Range::non_negative());
    threshold_ = t.number_or("trend_threshold_mW_cm2_per_s", 1.0, Range::non_negative());
    settle_s_ = t.number_or("settle_s", 1.5, Range::non_negative());
    if (!(unfold_below_ < fold_above_)) t.fail("fold_above_mW_cm2", "must be greater than unfold_below_mW_cm2");
    if (folded_ == unfolded_) t.fail("folded_deg", "must differ from unfolded_deg");
  }

  void update(double value, double time_s) override {
    // (A photodiode's dark offset, a little below 0, is a reading.)
    if (!std::isfinite(value)) throw gtrack::Error("light_intensity: a reading that is not a number; expected mW/cm2");
    rate_ = have_ && time_s > t_ ? (value - value_) / (time_s - t_) : 0.0;
    const int region = value >= fold_above_ ? 1 : value <= unfold_below_ ? -1 : 0;
    // A log that starts outside the band starts settled.
    if (region != region_) region_since_ = have_ ? time_s : time_s - settle_s_;
    region_ = region;
    value_ = value;
    t_ = time_s;
    have_ = true;
  }

  gtrack::StimulusState state() const override {
    gtrack::StimulusState s;
    s.value = value_;
    s.rate = rate_;
    s.trend = rate_ > threshold_ ? gtrack::StimulusTrend::Folding
              : rate_ < -threshold_ ? gtrack::StimulusTrend::Unfolding
                                    : gtrack::StimulusTrend::Steady;
    s.in_transition = region_ == 0 || t_ - region_since_ < settle_s_;
    const double ref = value_ >= fold_above_ ? folded_ : unfolded_;
    if (s.in_transition) {
      s.feasible_min_deg = std::min(unfolded_, folded_) - tolerance_;
      s.feasible_max_deg = std::max(unfolded_, folded_) + tolerance_;
    } else {
      s.feasible_min_deg = ref - tolerance_;
      s.feasible_max_deg = ref + tolerance_;
    }
    return s;
  }

  double penalty(std::span<const double> q) const override {
    const auto s = state();
    double sum = 0;
    int n = 0;
    for (double v : q) {
      if (v < s.feasible_min_deg) sum += s.feasible_min_deg + tolerance_ - v, ++n;
      else if (v > s.feasible_max_deg) sum += v - (s.feasible_max_deg - tolerance_), ++n;
    }
    return n ? sum / n / std::abs(folded_ - unfolded_) : 0.0;
  }

  // Share of the swarm whose joints start increased: towards folded_deg
  // while folding, whichever way that is.
  double fold_fraction() const override {
    const auto s = state();
    if (!s.in_transition || s.trend == gtrack::StimulusTrend::Steady) return 0.5;
    const bool towards_folded = s.trend == gtrack::StimulusTrend::Folding;
    const bool folding_increases = folded_ > unfolded_;
    return towards_folded == folding_increases ? 0.75 : 0.25;
  }

  double target_joint_deg(double current) const override {
    if (value_ >= fold_above_) return folded_;
    if (value_ <= unfold_below_) return unfolded_;
    return current;
  }

  std::string reading_label() const override { return "I"; }
  std::string reading_unit() const override { return "mW/cm2"; }

 private:
  double unfold_below_, fold_above_, unfolded_, folded_, tolerance_, threshold_, settle_s_;
  double value_ = 0, rate_ = 0, t_ = 0, region_since_ = 0;
  int region_ = 0;  // -1 below the band, 0 in it, 1 above
  bool have_ = false;
};

}  // namespace

GTRACK_PLUGIN(LightIntensity, gtrack::Stimulus, "light_intensity", "0.1.0",
              "photo-responsive folding driven by irradiance (mW/cm2)")
