// field_latch: a gripper whose hinges a magnetic field releases, its log in
// millitesla. The whole behaviour is gtrack's hysteresis model
// (gtrack/hysteresis_stimulus.hpp: a latch or a reversible band, the
// material's settle time or response, S(H) and the swarm's bias); the
// plugin only names its keys and its unit. Keys: mode ("latching" for a
// latch; "reversible", the default, for a band), trigger_mT (8),
// unfold_below_mT and fold_above_mT (2 and 8), trend_threshold_mT_per_s
// (0.05), and the model's common keys (folded_deg, tolerance_deg, settle_s,
// response_s, ...).
// Readings outside 0 to 100 mT are refused.
#include <gtrack/hysteresis_stimulus.hpp>
#include <gtrack/plugin.hpp>

namespace {

gtrack::HysteresisUnits millitesla() {
  gtrack::HysteresisUnits u;
  u.key_suffix = "_mT";  // trigger_mT, unfold_below_mT, fold_above_mT
  u.trend_key = "trend_threshold_mT_per_s";
  u.trend_default = 0.05;
  u.trigger = 8.0;
  u.unfold_below = 2.0;
  u.fold_above = 8.0;
  u.lowest = 0;
  u.highest = 100;
  u.label = "B";
  u.unit = "mT";
  u.quantity = "millitesla";
  return u;
}

class FieldLatch final : public gtrack::HysteresisStimulus {
 public:
  explicit FieldLatch(const gtrack::ConfigTable& t) : HysteresisStimulus(t, millitesla()) {}
};

}  // namespace

GTRACK_PLUGIN(FieldLatch, gtrack::Stimulus, "field_latch", "0.1.0",
              "hinges released by a magnetic field (mT): gtrack's hysteresis model, latched or reversible")
