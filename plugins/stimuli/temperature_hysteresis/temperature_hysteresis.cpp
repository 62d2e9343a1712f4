// temperature_hysteresis: thermally responsive grippers (paper 2.2, 3, 5).
//
// The threshold-and-hysteresis model of gtrack/hysteresis_stimulus.hpp with
// readings in degrees Celsius: keys `unfold_below_C` (24), `fold_above_C`
// (27) for a reversible hydrogel, `trigger_C` (37) for a latching metallic
// gripper, `trend_threshold_C_per_s` (0.005). The folding range is entered
// 0.5 C before its nominal edges. A reading outside -50 to 150 C, the range
// its thresholds may take, is not a temperature in Celsius (a log in kelvin
// or of another quantity): update() refuses it rather than fold the model
// by it. `log_unit = "F"` or `"K"` takes a log in Fahrenheit or kelvin (the
// thresholds stay in Celsius); a log in Fahrenheit read as Celsius would
// look plausible and fold the model at the wrong temperature.
#include <gtrack/hysteresis_stimulus.hpp>
#include <gtrack/plugin.hpp>
#include <string>

namespace {

gtrack::HysteresisUnits celsius(const gtrack::ConfigTable& t) {
  gtrack::HysteresisUnits u;
  const std::string log_unit = t.choice_or("log_unit", "C", {"C", "F", "K"});
  u.key_suffix = "_C";
  u.trend_key = "trend_threshold_C_per_s";
  u.trend_default = 0.005;
  u.unfold_below = 24.0;
  u.fold_above = 27.0;
  u.trigger = 37.0;
  u.lowest = -50;
  u.highest = 150;
  u.band_margin = 0.5;
  u.label = "T";
  u.unit = log_unit;
  if (log_unit == "C") {
    u.quantity = "degrees Celsius";
    u.refused_hint = [](double value) {
      return std::string(value > 200 && value < 500 ? " (kelvin: subtract 273.15, or set log_unit = \"K\")" : "");
    };
  } else if (log_unit == "F") {
    u.quantity = "degrees Fahrenheit (log_unit = \"F\")";
    u.reading_scale = 5.0 / 9.0;
    u.reading_offset = -32.0 * 5.0 / 9.0;
  } else {
    u.quantity = "kelvin (log_unit = \"K\")";
    u.reading_offset = -273.15;
  }
  return u;
}

class TemperatureHysteresis final : public gtrack::HysteresisStimulus {
 public:
  explicit TemperatureHysteresis(const gtrack::ConfigTable& t) : HysteresisStimulus(t, celsius(t)) {}
};

}  // namespace

GTRACK_PLUGIN(TemperatureHysteresis, gtrack::Stimulus, "temperature_hysteresis", "1.0.0",
              "thermally responsive folding: reversible hysteresis band (hydrogel) or latching trigger (metallic)")
