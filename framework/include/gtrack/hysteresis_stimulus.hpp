// A stimulus whose reading folds the gripper past a threshold, with a
// hysteresis band or a latch: the model behind the built-in
// `temperature_hysteresis` (readings in degrees Celsius) and
// `threshold_hysteresis` (readings in any unit the config names), and a
// base for a plugin of another quantity (a light's intensity, a magnetic
// field) that wants the same behaviour under key names of its own.
//
// Two behaviours, chosen by the table's `mode`:
//   reversible (hydrogel): unfolded at or below `unfold_below`, folded at or
//     above `fold_above`, anywhere in between while the reading crosses that
//     range (the hysteresis band, 24-27 C for pNIPAM-AAc);
//   latching (metallic): unfolded until the reading first reaches `trigger`
//     (37 C: the polymer trigger softens), then free to fold, and never
//     unfolds again (`triggered = true`: the latch closed before the
//     recording).
// S(H) is the paper's rule: joints outside the band the state allows are
// infeasible; S is the mean absolute error of those joints against the
// reference value (unfolded_deg or folded_deg, with `tolerance_deg`),
// divided by |folded - unfolded| so that it is comparable with D in [0, 1].
// The swarm bias is the paper's: `fold_bias` (0.75) of the particles start
// with increased joints while the reading rises in the folding range, 1 -
// fold_bias while it falls in it, half otherwise; a trend is a smoothed rate
// (over `trend_smoothing_s`) beyond the trend threshold.
// A material does not change shape the instant the reading crosses the
// band: for `settle_s` seconds after it enters the folded or unfolded range,
// the joints are still allowed anywhere between the references (0 gives the
// instantaneous rule). With `response_s` > 0 the plugin follows the
// material's response instead: the fold the gripper can have reached is
// integrated from the readings as a first-order lag towards
// target_joint_deg, with a time constant known within a factor of two
// (response_s / 2 to 2 response_s), and the joints are feasible within
// `tolerance_deg` of that interval.
// A reading outside the range the units allow is refused by update().
#pragma once

#include <optional>
#include <span>
#include <string>

#include "gtrack/config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/stimulus.hpp"

namespace gtrack {

// How a hysteresis stimulus names its keys and takes its readings.
struct HysteresisUnits {
  // Appended to the reading's keys: "unfold_below" + "_C".
  std::string key_suffix;
  // The trend threshold's key and default (readings per second).
  std::string trend_key = "trend_threshold_per_s";
  double trend_default = 0.005;
  // The thresholds' defaults; nullopt: the key is required in the mode
  // that reads it.
  std::optional<double> unfold_below, fold_above, trigger;
  // A reading in the log's unit is reading_scale * value + reading_offset
  // in the thresholds' (a log in Fahrenheit for thresholds in Celsius).
  double reading_scale = 1, reading_offset = 0;
  // Readings (and thresholds) outside [lowest, highest], in the
  // thresholds' unit, are refused.
  double lowest = -1e9, highest = 1e9;
  // The folding range is entered this far before its nominal edges.
  double band_margin = 0;
  // For the overlay and messages: "T", the log's unit ("C"), and what a
  // reading is ("degrees Celsius"); `refused_hint` is added to the message
  // of a refused reading (a kelvin log's, say) when it returns text for it.
  std::string label = "s", unit, quantity = "the plugin's unit";
  std::string (*refused_hint)(double value) = nullptr;
};

// A plugin deriving from it holds its members: a plugin built against one
// gtrack release is refused by another whose plugin ABI differs
// (GTRACK_PLUGIN_ABI_VERSION), which a change to this class's layout bumps.
class GTRACK_API HysteresisStimulus : public Stimulus {
 public:
  // Reads the table's keys (named as `units` says) and fails on any that
  // is out of range; the caller calls table.check_all_used() after
  // reading keys of its own, as every plugin constructor does.
  HysteresisStimulus(const ConfigTable& table, HysteresisUnits units);

  void update(double value, double time_s) override;
  StimulusState state() const override { return state_; }
  double penalty(std::span<const double> joints_deg) const override;
  double fold_fraction() const override;
  double target_joint_deg(double current_deg) const override;
  std::string reading_label() const override { return units_.label; }
  std::string reading_unit() const override { return units_.unit; }

 private:
  void refresh();
  void follow_response(double time_s);
  void set_range(double lo_ref, double hi_ref);

  HysteresisUnits units_;
  std::string name_;
  bool latching_ = false;
  double unfold_below_ = 0, fold_above_ = 0, trigger_ = 0, unfolded_ = 0, folded_ = 60, tolerance_ = 10;
  double min_rate_ = 0, smoothing_s_ = 2, fold_bias_ = 0.75, settle_s_ = 3, response_s_ = 0;
  StimulusState state_;
  double low_ref_ = 0, high_ref_ = 0;
  double reach_lo_ = 0, reach_hi_ = 0, reach_time_ = 0;
  bool has_reach_ = false;
  double prev_time_ = 0, now_ = 0, region_since_ = 0;
  int region_ = 2;            // none yet
  bool first_region_ = true;  // a sequence that starts beyond the band starts settled
  bool has_prev_ = false;
  bool triggered_ = false;
};

}  // namespace gtrack
