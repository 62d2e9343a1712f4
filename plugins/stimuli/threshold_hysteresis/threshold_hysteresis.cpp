// threshold_hysteresis: temperature_hysteresis's model for a reading of any
// quantity (a light's intensity, a magnetic field, a voltage), its unit
// named by the config.
//
// Keys, beside the common ones of gtrack/hysteresis_stimulus.hpp (mode,
// unfolded_deg, folded_deg, tolerance_deg, trend_smoothing_s, fold_bias,
// settle_s, response_s, triggered):
//   unfold_below, fold_above (required with mode = "reversible"), trigger
//     (required with mode = "latching"), in the reading's unit;
//   trend_threshold_per_s: the smallest smoothed rate counted as a trend
//     (default 1 % of the band, fold_above - unfold_below, per second; with
//     a latch 0);
//   band_margin: the folding range is entered this far before its edges (0);
//   reading_min, reading_max: the readings taken (unbounded by default); a
//     reading outside is refused, as a log in another unit would be;
//   label, unit: how the overlay names the reading ("s", "").
#include <cmath>
#include <gtrack/hysteresis_stimulus.hpp>
#include <gtrack/plugin.hpp>
#include <string>

namespace {

gtrack::HysteresisUnits from_table(const gtrack::ConfigTable& t) {
  using gtrack::Range;
  gtrack::HysteresisUnits u;
  u.lowest = t.number_or("reading_min", -1e9, Range::closed(-1e9, 1e9));
  u.highest = t.number_or("reading_max", 1e9, Range::closed(-1e9, 1e9));
  if (!(u.lowest < u.highest)) t.fail("reading_max", "must be greater than reading_min");
  u.band_margin = t.number_or("band_margin", 0.0, Range::non_negative());
  u.label = t.string_or("label", "s");
  u.unit = t.string_or("unit", "");
  u.quantity = "a reading within reading_min and reading_max";
  u.trend_key = "trend_threshold_per_s";
  const bool reversible = t.string_or("mode", "reversible") == "reversible";
  if (reversible && t.has("unfold_below") && t.has("fold_above")) {
    u.trend_default = 0.01 * std::abs(t.number("fold_above") - t.number("unfold_below"));
  } else {
    u.trend_default = 0;
  }
  return u;
}

class ThresholdHysteresis final : public gtrack::HysteresisStimulus {
 public:
  explicit ThresholdHysteresis(const gtrack::ConfigTable& t) : HysteresisStimulus(t, from_table(t)) {}
};

}  // namespace

GTRACK_PLUGIN(ThresholdHysteresis, gtrack::Stimulus, "threshold_hysteresis", "1.0.0",
              "folding past a threshold of a reading in any unit (light, field): hysteresis band or latch")
