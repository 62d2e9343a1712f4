// The threshold-and-hysteresis stimulus model (gtrack/hysteresis_stimulus.hpp).
#include "gtrack/hysteresis_stimulus.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "gtrack/error.hpp"

namespace gtrack {

HysteresisStimulus::HysteresisStimulus(const ConfigTable& t, HysteresisUnits units) : units_(std::move(units)) {
  const Range readings = Range::closed(units_.lowest, units_.highest);
  const std::string& sfx = units_.key_suffix;
  latching_ = t.choice_or("mode", "reversible", {"reversible", "latching"}) == "latching";
  const std::string unfold_key = "unfold_below" + sfx, fold_key = "fold_above" + sfx, trigger_key = "trigger" + sfx;
  // A threshold of the other mode would be left unread, and the gripper
  // folded by the defaults of this one.
  for (const std::string& key : {unfold_key, fold_key, trigger_key, std::string("triggered")}) {
    const bool latch_key = key.rfind("trigger", 0) == 0;
    if (t.has(key) && latch_key != latching_) {
      t.fail(key, std::string("is read only with mode = \"") + (latching_ ? "reversible" : "latching") + "\" (" +
                      (latching_ ? "a hydrogel's fold both ways" : "a metallic gripper's one-way fold") +
                      "); set that mode, or remove the key");
    }
  }
  // A threshold without a default is required by the mode that reads it.
  const auto threshold = [&](const std::string& key, const std::optional<double>& fallback, bool read) {
    if (fallback) return t.number_or(key, *fallback, readings);
    return read ? t.number(key, readings) : 0.0;
  };
  unfold_below_ = threshold(unfold_key, units_.unfold_below, !latching_);
  fold_above_ = threshold(fold_key, units_.fold_above, !latching_);
  trigger_ = threshold(trigger_key, units_.trigger, latching_);
  unfolded_ = t.number_or("unfolded_deg", 0.0, Range::closed(-180, 180));
  folded_ = t.number_or("folded_deg", 60.0, Range::closed(-180, 180));
  tolerance_ = t.number_or("tolerance_deg", 10.0, Range::non_negative());
  min_rate_ = t.number_or(units_.trend_key, units_.trend_default, Range::non_negative());
  smoothing_s_ = t.number_or("trend_smoothing_s", 2.0, Range::positive());
  fold_bias_ = t.number_or("fold_bias", 0.75, Range::closed(0.5, 1.0));
  settle_s_ = t.number_or("settle_s", 3.0, Range::non_negative());
  response_s_ = t.number_or("response_s", 0.0, Range::non_negative());
  // The latch closed before the recording's first frame (a gripper heated
  // earlier): the log's readings need not reach the trigger.
  triggered_ = t.boolean_or("triggered", false);
  if (!latching_ && !(unfold_below_ < fold_above_)) t.fail(fold_key, "must be greater than " + unfold_key);
  if (folded_ == unfolded_) t.fail("folded_deg", "must differ from unfolded_deg");
  name_ = t.string_or("plugin", "the stimulus plugin");
  state_.value = latching_ && !units_.unfold_below ? trigger_ : unfold_below_;
  refresh();
}

void HysteresisStimulus::update(double reading, double time_s) {
  // In the thresholds' unit.
  const double value = reading * units_.reading_scale + units_.reading_offset;
  if (std::isfinite(value) && (value < units_.lowest || value > units_.highest)) {
    // Said in the log's unit.
    const double a = (units_.lowest - units_.reading_offset) / units_.reading_scale;
    const double b = (units_.highest - units_.reading_offset) / units_.reading_scale;
    const std::string hint = units_.refused_hint ? units_.refused_hint(reading) : std::string();
    throw InputError(fmt::format("a reading of {:g}, outside the {:g} to {:g}{} {} takes: expected {}{}", reading,
                                 std::min(a, b), std::max(a, b), units_.unit.empty() ? "" : " " + units_.unit, name_,
                                 units_.quantity, hint));
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
    if (latching_ && value >= trigger_) triggered_ = true;
    if (response_s_ > 0) follow_response(time_s);
  }
  refresh();
}

double HysteresisStimulus::penalty(std::span<const double> q) const {
  double sum = 0;
  int infeasible = 0;
  for (double v : q) {
    if (v >= state_.feasible_min_deg && v <= state_.feasible_max_deg) continue;
    sum += std::abs(v - (v < state_.feasible_min_deg ? low_ref_ : high_ref_));
    ++infeasible;
  }
  return infeasible ? sum / infeasible / std::abs(folded_ - unfolded_) : 0.0;
}

double HysteresisStimulus::fold_fraction() const {
  // Folding means moving from unfolded_deg towards folded_deg.
  const double toward_fold = folded_ > unfolded_ ? fold_bias_ : 1.0 - fold_bias_;
  switch (state_.trend) {
    case StimulusTrend::Folding: return state_.in_transition ? toward_fold : 0.5;
    case StimulusTrend::Unfolding: return state_.in_transition ? 1.0 - toward_fold : 0.5;
    default: return 0.5;
  }
}

double HysteresisStimulus::target_joint_deg(double current) const {
  const double T = state_.value;
  if (latching_) return triggered_ ? folded_ : current;
  if (T >= fold_above_) return folded_;
  if (T <= unfold_below_) return unfolded_;
  const double s = (T - unfold_below_) / (fold_above_ - unfold_below_);
  const double level = unfolded_ + s * (folded_ - unfolded_);
  // Hysteresis: a rising reading only folds further, a falling one only unfolds.
  const bool folded_more = (folded_ > unfolded_) ? level > current : level < current;
  if (state_.rate > 0) return folded_more ? level : current;
  if (state_.rate < 0) return folded_more ? current : level;
  return current;
}

void HysteresisStimulus::refresh() {
  const double T = state_.value;
  state_.trend = state_.rate > min_rate_    ? StimulusTrend::Folding
                 : state_.rate < -min_rate_ ? StimulusTrend::Unfolding
                                            : StimulusTrend::Steady;
  if (latching_) {
    state_.in_transition = triggered_;
    // Folding is still under way: the trend is folding while triggered.
    if (triggered_) state_.trend = StimulusTrend::Folding;
  } else {
    state_.in_transition = T > unfold_below_ - units_.band_margin && T < fold_above_ + units_.band_margin;
  }
  if (response_s_ > 0 && has_reach_) {
    // The reachable folds, widened by the tolerance.
    set_range(reach_lo_, reach_hi_);
    if (!latching_ && reach_hi_ - reach_lo_ > tolerance_) state_.in_transition = true;
    return;
  }
  const double open_or_closed_lo = std::min(unfolded_, folded_), open_or_closed_hi = std::max(unfolded_, folded_);
  if (latching_) {
    if (triggered_) {
      set_range(open_or_closed_lo, open_or_closed_hi);
    } else {
      set_range(unfolded_, unfolded_);
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
    set_range(folded_, folded_);
  } else if (region == -1 && settled) {
    set_range(unfolded_, unfolded_);
  } else {
    set_range(open_or_closed_lo, open_or_closed_hi);
    if (region != 0) state_.in_transition = true;
  }
}

// One step of the response: each end of the reachable interval moves
// towards its target, the upper end fast when folding up and slowly when
// coming down, the lower end the other way round, so that every material
// whose time constant lies in [response_s / 2, 2 response_s] stays inside.
void HysteresisStimulus::follow_response(double time_s) {
  const bool latched_unfolded = latching_ && !triggered_;
  if (!has_reach_) {
    // A sequence that starts cold starts unfolded, one that starts hot
    // folded (as with settle_s); otherwise the fold is not known yet.
    const double T = state_.value;
    const bool cold = latched_unfolded || (!latching_ && T <= unfold_below_);
    const bool hot = !latching_ && T >= fold_above_;
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
void HysteresisStimulus::set_range(double lo_ref, double hi_ref) {
  state_.feasible_min_deg = lo_ref - tolerance_;
  state_.feasible_max_deg = hi_ref + tolerance_;
  low_ref_ = lo_ref;
  high_ref_ = hi_ref;
}

}  // namespace gtrack
