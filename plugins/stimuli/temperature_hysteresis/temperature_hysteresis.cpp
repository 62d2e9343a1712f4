// temperature_hysteresis: thermally responsive grippers (paper 2.2, 3, 5).
//
// Two behaviours, chosen by `mode`:
//   reversible (hydrogel): unfolded at or below `unfold_below_C`, folded at or
//     above `fold_above_C`, anywhere in between while the temperature crosses
//     that range (the hysteresis band, 24-27 C for pNIPAM-AAc);
//   latching (metallic): unfolded until the temperature first reaches
//     `trigger_C` (37 C: the polymer trigger softens), then free to fold, and
//     never unfolds again.
// S(H) is the paper's rule: joints outside the band the state allows are
// infeasible; S is the mean absolute error of those joints against the
// reference value (unfolded_deg or folded_deg, with `tolerance_deg`),
// divided by |folded - unfolded| so that it is comparable with D in [0, 1].
// The swarm bias is the paper's: 75% of particles start with increased joints
// when heating in the folding range, 25% when cooling in it, 50% otherwise.
// A material does not change shape the instant the temperature crosses the
// band: for `settle_s` seconds after it enters the folded or unfolded range,
// the joints are still allowed anywhere between the references (0 gives the
// instantaneous rule).
// With `response_s` > 0 the plugin also follows the material's response: the
// fold the gripper can have reached is integrated from the readings as a
// first-order lag towards target_joint_deg, with a time constant known within
// a factor of two (response_s / 2 to 2 response_s). The joints are then
// feasible within `tolerance_deg` of that interval, which replaces settle_s:
// during a fold the allowed range moves with the fold instead of spanning
// every value between the references.
// A reading outside -50 to 150 C, the range its thresholds may take, is not
// a temperature in Celsius (a log in kelvin or of another quantity): update()
// refuses it rather than fold the model by it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtrack/error.hpp>
#include <gtrack/plugin.hpp>
#include <string>

namespace {

// The folding range is entered slightly before its nominal edges.
constexpr double kBandMarginC = 0.5;
// The temperatures the plugin takes, in its thresholds and its readings.
constexpr double kLowestC = -50, kHighestC = 150;

class TemperatureHysteresis final : public gtrack::Stimulus {
 public:
  explicit TemperatureHysteresis(const gtrack::ConfigTable& t) {
    using gtrack::Range;
    mode_ = t.choice_or("mode", "reversible", {"reversible", "latching"});
    unfold_below_ = t.number_or("unfold_below_C", 24.0, Range::closed(kLowestC, kHighestC));
    fold_above_ = t.number_or("fold_above_C", 27.0, Range::closed(kLowestC, kHighestC));
    trigger_ = t.number_or("trigger_C", 37.0, Range::closed(kLowestC, kHighestC));
    unfolded_ = t.number_or("unfolded_deg", 0.0, Range::closed(-180, 180));
    folded_ = t.number_or("folded_deg", 60.0, Range::closed(-180, 180));
    tolerance_ = t.number_or("tolerance_deg", 10.0, Range::non_negative());
    min_rate_ = t.number_or("trend_threshold_C_per_s", 0.005, Range::non_negative());
    smoothing_s_ = t.number_or("trend_smoothing_s", 2.0, Range::positive());
    fold_bias_ = t.number_or("fold_bias", 0.75, Range::closed(0.5, 1.0));
    settle_s_ = t.number_or("settle_s", 3.0, Range::non_negative());
    response_s_ = t.number_or("response_s", 0.0, Range::non_negative());
    // A threshold of the other mode would be left unread, and the gripper
    // folded by the defaults of this one.
    const bool latching = mode_ == "latching";
    for (const char* key : {"unfold_below_C", "fold_above_C", "trigger_C", "triggered"}) {
      const bool latch_key = std::string(key).rfind("trigger", 0) == 0;
      if (t.has(key) && latch_key != latching) {
        t.fail(key, std::string("is read only with mode = \"") + (latching ? "reversible" : "latching") + "\" (" +
                        (latching ? "a hydrogel's fold both ways" : "a metallic gripper's one-way fold") +
                        "); set that mode, or remove the key");
      }
    }
    // The latch closed before the recording's first frame (a gripper heated
    // earlier): the log's readings need not reach trigger_C.
    triggered_ = t.boolean_or("triggered", false);
    if (!latching && !(unfold_below_ < fold_above_)) {
      t.fail("fold_above_C", "must be greater than unfold_below_C");
    }
    if (folded_ == unfolded_) t.fail("folded_deg", "must differ from unfolded_deg");
    state_.value = unfold_below_;
    refresh();
  }

  void update(double value, double time_s) override {
    if (std::isfinite(value) && (value < kLowestC || value > kHighestC)) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "a reading of %g, outside the %g to %g C temperature_hysteresis takes: expected degrees Celsius%s",
                    value, kLowestC, kHighestC, value > 200 && value < 500 ? " (kelvin: subtract 273.15)" : "");
      throw gtrack::InputError(text);
    }
    if (std::isfinite(value)) {
      if (has_prev_ && time_s > prev_time_) {
        const double raw = (value - state_.value) / (time_s - prev_time_);
        const double a = std::min(1.0, (time_s - prev_time_) / smoothing_s_);
        state_.rate += a * (raw - state_.rate);
      }
      state_.value = value;
      now_ = time_s;
      prev_time_ = time_s;
      has_prev_ = true;
      if (mode_ == "latching" && value >= trigger_) triggered_ = true;
      if (response_s_ > 0) follow_response(time_s);
    }
    refresh();
  }

  gtrack::StimulusState state() const override { return state_; }

  double penalty(std::span<const double> q) const override {
    double sum = 0;
    int infeasible = 0;
    for (double v : q) {
      if (v >= state_.feasible_min_deg && v <= state_.feasible_max_deg) continue;
      sum += std::abs(v - (v < state_.feasible_min_deg ? low_ref_ : high_ref_));
      ++infeasible;
    }
    return infeasible ? sum / infeasible / std::abs(folded_ - unfolded_) : 0.0;
  }

  double fold_fraction() const override {
    // Folding means moving from unfolded_deg towards folded_deg.
    const double toward_fold = folded_ > unfolded_ ? fold_bias_ : 1.0 - fold_bias_;
    switch (state_.trend) {
      case gtrack::StimulusTrend::Folding: return state_.in_transition ? toward_fold : 0.5;
      case gtrack::StimulusTrend::Unfolding: return state_.in_transition ? 1.0 - toward_fold : 0.5;
      default: return 0.5;
    }
  }

  double target_joint_deg(double current) const override {
    const double T = state_.value;
    if (mode_ == "latching") return triggered_ ? folded_ : current;
    if (T >= fold_above_) return folded_;
    if (T <= unfold_below_) return unfolded_;
    const double s = (T - unfold_below_) / (fold_above_ - unfold_below_);
    const double level = unfolded_ + s * (folded_ - unfolded_);
    // Hysteresis: heating only folds further, cooling only unfolds.
    const bool folded_more = (folded_ > unfolded_) ? level > current : level < current;
    if (state_.rate > 0) return folded_more ? level : current;
    if (state_.rate < 0) return folded_more ? current : level;
    return current;
  }

  std::string reading_label() const override { return "T"; }
  std::string reading_unit() const override { return "C"; }

 private:
  void refresh() {
    const double T = state_.value;
    state_.trend = state_.rate > min_rate_    ? gtrack::StimulusTrend::Folding
                   : state_.rate < -min_rate_ ? gtrack::StimulusTrend::Unfolding
                                              : gtrack::StimulusTrend::Steady;
    const bool latching = mode_ == "latching";
    if (latching) {
      state_.in_transition = triggered_;
      // Folding is still under way: the trend is folding while triggered.
      if (triggered_) state_.trend = gtrack::StimulusTrend::Folding;
    } else {
      state_.in_transition = T > unfold_below_ - kBandMarginC && T < fold_above_ + kBandMarginC;
    }
    if (response_s_ > 0 && has_reach_) {
      // The reachable folds, widened by the tolerance.
      set_range(reach_lo_, reach_hi_);
      if (!latching && reach_hi_ - reach_lo_ > tolerance_) state_.in_transition = true;
      return;
    }
    const double open_or_closed_lo = std::min(unfolded_, folded_), open_or_closed_hi = std::max(unfolded_, folded_);
    if (latching) {
      if (triggered_) {
        set_range(open_or_closed_lo, open_or_closed_hi);
      } else {
        set_band(unfolded_);
      }
      return;
    }
    const int region = T >= fold_above_ ? 1 : T <= unfold_below_ ? -1 : 0;
    // Regions are counted from the first reading (not from the constructor's
    // placeholder value), so that a sequence starting hot starts settled.
    if (has_prev_ && region != region_) {
      if (region_ != 2) first_region_ = false;
      region_ = region;
      region_since_ = now_;
    }
    const bool settled = first_region_ || now_ - region_since_ >= settle_s_;
    if (region == 1 && settled) {
      set_band(folded_);
    } else if (region == -1 && settled) {
      set_band(unfolded_);
    } else {
      set_range(open_or_closed_lo, open_or_closed_hi);
      if (region != 0) state_.in_transition = true;
    }
  }

  // One step of the response: each end of the reachable interval moves
  // towards its target, the upper end fast when folding up and slowly when
  // coming down, the lower end the other way round, so that every material
  // whose time constant lies in [response_s / 2, 2 response_s] stays inside.
  void follow_response(double time_s) {
    const bool latched_unfolded = mode_ == "latching" && !triggered_;
    if (!has_reach_) {
      // A sequence that starts cold starts unfolded, one that starts hot
      // folded (as with settle_s); otherwise the fold is not known yet.
      const double T = state_.value;
      const bool cold = latched_unfolded || (mode_ == "reversible" && T <= unfold_below_);
      const bool hot = mode_ == "reversible" && T >= fold_above_;
      reach_lo_ = cold ? unfolded_ : hot ? folded_ : std::min(unfolded_, folded_);
      reach_hi_ = cold ? unfolded_ : hot ? folded_ : std::max(unfolded_, folded_);
      has_reach_ = true;
      reach_time_ = time_s;
      return;
    }
    const double dt = time_s - reach_time_;
    if (dt <= 0) return;
    reach_time_ = time_s;
    auto step = [&](double q, bool upper) {
      const double target = target_joint_deg(q);
      const bool fast = (target > q) == upper;
      const double tau = fast ? 0.5 * response_s_ : 2.0 * response_s_;
      return q + (target - q) * (1 - std::exp(-dt / tau));
    };
    const double lo = step(reach_lo_, false), hi = step(reach_hi_, true);
    reach_lo_ = std::min(lo, hi);
    reach_hi_ = std::max(lo, hi);
  }

  // Joints within tolerance_deg of [lo_ref, hi_ref] are feasible; the
  // penalty of the others is taken against the nearer reference.
  void set_range(double lo_ref, double hi_ref) {
    state_.feasible_min_deg = lo_ref - tolerance_;
    state_.feasible_max_deg = hi_ref + tolerance_;
    low_ref_ = lo_ref;
    high_ref_ = hi_ref;
  }

  void set_band(double ref) { set_range(ref, ref); }

  std::string mode_;
  double unfold_below_, fold_above_, trigger_, unfolded_, folded_, tolerance_, min_rate_, smoothing_s_, fold_bias_;
  gtrack::StimulusState state_;
  double low_ref_ = 0, high_ref_ = 0;
  double settle_s_ = 3.0;
  double response_s_ = 0.0;
  double reach_lo_ = 0, reach_hi_ = 0, reach_time_ = 0;
  bool has_reach_ = false;
  double prev_time_ = 0, now_ = 0, region_since_ = 0;
  int region_ = 2;            // none yet
  bool first_region_ = true;  // a sequence that starts hot or cold starts settled
  bool has_prev_ = false;
  bool triggered_ = false;
};

}  // namespace

GTRACK_PLUGIN(TemperatureHysteresis, gtrack::Stimulus, "temperature_hysteresis", "1.0.0",
              "thermally responsive folding: reversible hysteresis band (hydrogel) or latching trigger (metallic)")
