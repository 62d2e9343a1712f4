// temperature_hysteresis against the paper's rules (Sections 2.2, 3, 5), and
// the setup's check of a stimulus's reference joints against the gripper's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/setup.hpp"
#include "support/logged.hpp"
#include "support/plugins.hpp"

using gtrack::testing::make_stimulus;

namespace {

const char* kHydrogel = "plugin = \"temperature_hysteresis\"";
const char* kMetallic =
    "plugin = \"temperature_hysteresis\"\nmode = \"latching\"\ntrigger_C = 37\nfolded_deg = 70\ntolerance_deg = 8";

void ramp(gtrack::Stimulus& s, double from, double to, int steps, double t0 = 0, double dt = 1) {
  for (int i = 0; i <= steps; ++i) s.update(from + (to - from) * i / steps, t0 + i * dt);
}

TEST(TemperatureHysteresis, HeatingInTheFoldingRangeBiasesThreeQuartersTowardsFolding) {
  auto s = make_stimulus(kHydrogel);
  ramp(*s, 23.0, 25.5, 20);
  EXPECT_EQ(s->state().trend, gtrack::StimulusTrend::Folding);
  EXPECT_TRUE(s->state().in_transition);
  EXPECT_DOUBLE_EQ(s->fold_fraction(), 0.75);
}

TEST(TemperatureHysteresis, CoolingInTheRangeBiasesTowardsUnfolding) {
  auto s = make_stimulus(kHydrogel);
  ramp(*s, 29.0, 25.5, 20);
  EXPECT_EQ(s->state().trend, gtrack::StimulusTrend::Unfolding);
  EXPECT_DOUBLE_EQ(s->fold_fraction(), 0.25);
}

TEST(TemperatureHysteresis, OtherwiseHalfAndHalf) {
  auto s = make_stimulus(kHydrogel);
  ramp(*s, 20.0, 20.0, 10);  // steady, outside the range
  EXPECT_DOUBLE_EQ(s->fold_fraction(), 0.5);
  auto h = make_stimulus(kHydrogel);
  ramp(*h, 30.0, 33.0, 10);  // heating, but far above the range
  EXPECT_FALSE(h->state().in_transition);
  EXPECT_DOUBLE_EQ(h->fold_fraction(), 0.5);
}

TEST(TemperatureHysteresis, PenaltyIsTheMeanAbsoluteErrorOfInfeasibleJoints) {
  auto s = make_stimulus(kHydrogel);
  ramp(*s, 30.0, 30.0, 3);  // hot from the start: folded (60 +- 10)
  std::vector<double> folded{60, 55, 65, 70, 50, 62};
  EXPECT_DOUBLE_EQ(s->penalty(folded), 0.0);
  std::vector<double> two_open{0, 30, 60, 60, 60, 60};  // 0 and 30 infeasible: MAE = (60 + 30)/2 = 45 deg
  EXPECT_NEAR(s->penalty(two_open), 45.0 / 60.0, 1e-12);
  auto c = make_stimulus(kHydrogel);
  ramp(*c, 20.0, 20.0, 3);  // cold: unfolded (0 +- 10)
  EXPECT_DOUBLE_EQ(c->penalty(std::vector<double>(6, 5.0)), 0.0);
  EXPECT_NEAR(c->penalty(std::vector<double>{60, 0, 0, 0, 0, 0}), 1.0, 1e-12);
  // In the transition band every value between the references is feasible.
  auto m = make_stimulus(kHydrogel);
  ramp(*m, 25.0, 26.0, 5);
  EXPECT_DOUBLE_EQ(m->penalty(std::vector<double>{0, 10, 30, 45, 60, 65}), 0.0);
  EXPECT_GT(m->penalty(std::vector<double>{0, 10, 30, 45, 60, 95}), 0.0);
}

TEST(TemperatureHysteresis, TheMaterialGetsTimeToSettle) {
  auto s = make_stimulus(kHydrogel);  // settle_s = 3 by default
  ramp(*s, 22.0, 28.0, 6);            // heated through the band, 28 C reached at t = 6 s
  const std::vector<double> lagging(6, 20.0);
  EXPECT_DOUBLE_EQ(s->penalty(lagging), 0.0);  // just arrived: still folding
  ramp(*s, 28.0, 28.0, 2, 7);                  // t = 9 s: 3 s above 27 C
  EXPECT_NEAR(s->penalty(lagging), 40.0 / 60.0, 1e-12);
  auto hot = make_stimulus(kHydrogel);  // a sequence that starts hot starts settled
  hot->update(30.0, 0.0);
  EXPECT_NEAR(hot->penalty(lagging), 40.0 / 60.0, 1e-12);
  auto instant = make_stimulus("plugin = \"temperature_hysteresis\"\nsettle_s = 0");
  ramp(*instant, 22.0, 28.0, 6);
  EXPECT_NEAR(instant->penalty(lagging), 40.0 / 60.0, 1e-12);
}

TEST(TemperatureHysteresis, HysteresisDrivesTheSimulatedJoint) {
  auto s = make_stimulus(kHydrogel);
  ramp(*s, 24.0, 25.5, 10);  // heating half-way through the band
  EXPECT_NEAR(s->target_joint_deg(0.0), 30.0, 1e-9);
  EXPECT_NEAR(s->target_joint_deg(50.0), 50.0, 1e-9);  // heating never unfolds
  ramp(*s, 25.5, 25.0, 10, 20);  // cooling slightly
  EXPECT_NEAR(s->target_joint_deg(50.0), 20.0, 1e-9);
  EXPECT_NEAR(s->target_joint_deg(10.0), 10.0, 1e-9);  // cooling never folds
}

TEST(TemperatureHysteresis, MetallicGrippersFoldAtTriggerAndNeverUnfold) {
  auto s = make_stimulus(kMetallic);
  ramp(*s, 25.0, 36.0, 10);
  EXPECT_GT(s->penalty(std::vector<double>(6, 70.0)), 0.0);  // cannot be folded before 37 C
  EXPECT_DOUBLE_EQ(s->target_joint_deg(0.0), 0.0);
  ramp(*s, 36.0, 38.0, 5, 20);
  EXPECT_DOUBLE_EQ(s->target_joint_deg(0.0), 70.0);
  EXPECT_DOUBLE_EQ(s->fold_fraction(), 0.75);
  ramp(*s, 38.0, 25.0, 10, 40);  // cooled again: stays folded
  EXPECT_DOUBLE_EQ(s->penalty(std::vector<double>(6, 70.0)), 0.0);
  EXPECT_DOUBLE_EQ(s->target_joint_deg(70.0), 70.0);
}

// A recording made after the gripper was heated: `triggered = true` starts
// with the latch closed, whatever the log reads.
TEST(TemperatureHysteresis, ALatchClosedBeforeTheRecordingIsSaidInTheTable) {
  auto s = make_stimulus(std::string(kMetallic) + "\ntriggered = true");
  ramp(*s, 25.0, 25.0, 5);
  EXPECT_DOUBLE_EQ(s->penalty(std::vector<double>(6, 70.0)), 0.0);
  EXPECT_DOUBLE_EQ(s->target_joint_deg(0.0), 70.0);
}

// A threshold of the other mode is refused, naming its key, rather than
// left unread while the gripper is folded by this mode's defaults (a
// metallic gripper given trigger_C without mode = "latching" was folded
// by the hydrogel's 24-27 C band).
TEST(TemperatureHysteresis, TheOtherModesKeysAreRefused) {
  const auto error = [](const std::string& table) {
    try {
      make_stimulus(table);
    } catch (const gtrack::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string hydrogel = error("plugin = \"temperature_hysteresis\"\ntrigger_C = 37");
  EXPECT_NE(hydrogel.find("key 'trigger_C': is read only with mode = \"latching\""), std::string::npos) << hydrogel;
  EXPECT_NE(error("plugin = \"temperature_hysteresis\"\ntriggered = true").find("key 'triggered'"),
            std::string::npos);
  const std::string metallic = error(std::string(kMetallic) + "\nfold_above_C = 40");
  EXPECT_NE(metallic.find("key 'fold_above_C': is read only with mode = \"reversible\""), std::string::npos)
      << metallic;
}

// A material with a first-order response of time constant tau, driven the
// way the synthetic sequences drive it, against the feasible range of a
// stimulus that knows the response time within a factor of two.
double worst_penalty_of_a_lagging_material(const std::string& table, double tau, const std::vector<double>& temps) {
  auto material = make_stimulus(table);  // the material's own state
  auto tracked = make_stimulus(table + "\nresponse_s = 0.5");
  const double dt = 1.0 / 30;
  double q = 0, worst = 0;
  for (std::size_t i = 0; i < temps.size(); ++i) {
    material->update(temps[i], i * dt);
    tracked->update(temps[i], i * dt);
    if (i > 0) q += (material->target_joint_deg(q) - q) * (1 - std::exp(-dt / tau));
    worst = std::max(worst, tracked->penalty(std::vector<double>(6, q)));
  }
  return worst;
}

std::vector<double> heat_and_cool(double low, double high, int frames) {
  std::vector<double> t;
  for (int i = 0; i < frames; ++i) t.push_back(0.5 * (low + high) - 0.5 * (high - low) * std::cos(2 * std::numbers::pi * i / 150.0));
  return t;
}

TEST(TemperatureHysteresis, TheResponseTimeKeepsTheFoldInsideAMovingRange) {
  // Every material whose time constant is within a factor of two of
  // response_s stays feasible through heating and cooling, in both modes.
  for (double tau : {0.26, 0.35, 0.5, 0.9}) {
    EXPECT_DOUBLE_EQ(worst_penalty_of_a_lagging_material(kHydrogel, tau, heat_and_cool(20, 32, 300)), 0.0) << tau;
    EXPECT_DOUBLE_EQ(worst_penalty_of_a_lagging_material(kMetallic, tau, heat_and_cool(30, 40, 300)), 0.0) << tau;
  }
  // A material far slower than that is not.
  EXPECT_GT(worst_penalty_of_a_lagging_material(kHydrogel, 3.0, heat_and_cool(20, 32, 300)), 0.0);

  // The range moves with the fold: just after the trigger a folded gripper
  // is infeasible (without response_s every fold up to 70 + 8 would be), and
  // once the fold is done an open one is (it never unfolds).
  auto s = make_stimulus(std::string(kMetallic) + "\nresponse_s = 0.5");
  ramp(*s, 30.0, 38.0, 8, 0, 0.1);  // 37 C is passed at t = 0.7 s, then 0.1 s more
  EXPECT_DOUBLE_EQ(s->penalty(std::vector<double>(2, 10.0)), 0.0);
  EXPECT_GT(s->penalty(std::vector<double>(2, 65.0)), 0.0);
  ramp(*s, 38.0, 30.0, 50, 1.0, 0.1);  // five seconds later, cooled again
  EXPECT_DOUBLE_EQ(s->penalty(std::vector<double>(2, 65.0)), 0.0);
  EXPECT_GT(s->penalty(std::vector<double>(2, 20.0)), 0.0);
  auto plain = make_stimulus(kMetallic);
  ramp(*plain, 30.0, 38.0, 8, 0, 0.1);
  EXPECT_DOUBLE_EQ(plain->penalty(std::vector<double>(2, 65.0)), 0.0);
  ramp(*plain, 38.0, 30.0, 50, 1.0, 0.1);
  EXPECT_DOUBLE_EQ(plain->penalty(std::vector<double>(2, 20.0)), 0.0);
}

// A reading no temperature of the plugin's range can be (a log in kelvin)
// is refused, saying what was expected; one at the range's ends is taken.
TEST(TemperatureHysteresis, RefusesAReadingThatIsNotCelsius) {
  auto s = make_stimulus(kHydrogel);
  EXPECT_NO_THROW(s->update(150, 0));
  EXPECT_NO_THROW(s->update(-50, 1));
  try {
    s->update(296.15, 2);
    ADD_FAILURE() << "a reading in kelvin was taken";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("expected degrees Celsius (kelvin: subtract 273.15, or set log_unit = \"K\")"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(s->update(-60, 3), gtrack::InputError);
  EXPECT_DOUBLE_EQ(s->state().value, -50);  // the refused readings changed nothing
}

// log_unit: a log in Fahrenheit or kelvin is taken as the same temperatures
// in Celsius (read as Celsius, 80 F had been a hot 80 C); the overlay's unit
// is the log's, and a refused reading is said in it.
TEST(TemperatureHysteresis, ALogInFahrenheitOrKelvinIsTheSameTemperatures) {
  const std::string settle = "\nsettle_s = 1";
  auto c = make_stimulus(std::string(kHydrogel) + settle);
  auto f = make_stimulus(std::string(kHydrogel) + settle + "\nlog_unit = \"F\"");
  auto k = make_stimulus(std::string(kHydrogel) + settle + "\nlog_unit = \"K\"");
  const std::vector<double> joints{-5, 12, 30, 61};
  for (int i = 0; i < 80; ++i) {
    const double celsius = 25.5 + 4.5 * std::sin(i / 9.0);  // through the 24-27 C band and back
    c->update(celsius, i / 10.0);
    f->update(celsius * 9 / 5 + 32, i / 10.0);
    k->update(celsius + 273.15, i / 10.0);
    for (const auto* other : {&f, &k}) {
      ASSERT_NEAR((*other)->state().feasible_min_deg, c->state().feasible_min_deg, 1e-9) << i;
      ASSERT_NEAR((*other)->state().feasible_max_deg, c->state().feasible_max_deg, 1e-9) << i;
      ASSERT_NEAR((*other)->penalty(joints), c->penalty(joints), 1e-9) << i;
      ASSERT_EQ((*other)->fold_fraction(), c->fold_fraction()) << i;
    }
  }
  EXPECT_EQ(f->reading_unit(), "F");
  EXPECT_EQ(k->reading_unit(), "K");
  try {
    f->update(400, 9);
    ADD_FAILURE() << "400 F was taken";
  } catch (const gtrack::InputError& e) {
    EXPECT_STREQ(e.what(), "a reading of 400, outside the -58 to 302 F temperature_hysteresis takes: expected degrees "
                           "Fahrenheit (log_unit = \"F\")");
  }
}

TEST(TemperatureHysteresis, BadTablesAreRejected) {
  EXPECT_THROW(make_stimulus("plugin = \"temperature_hysteresis\"\nmode = \"sometimes\""), gtrack::ConfigError);
  EXPECT_THROW(make_stimulus("plugin = \"temperature_hysteresis\"\nunfold_below_C = 30\nfold_above_C = 20"),
               gtrack::ConfigError);
  EXPECT_THROW(make_stimulus("plugin = \"temperature_hysteresis\"\nfold_bias = 2"), gtrack::ConfigError);
  EXPECT_THROW(make_stimulus("plugin = \"temperature_hysteresis\"\nresponse_s = -1"), gtrack::ConfigError);
}

// threshold_hysteresis is temperature_hysteresis's model in the units the
// config names: given the Celsius plugin's thresholds, margin and trend
// threshold, it follows the same readings to the same states, penalties
// and biases, in both modes.
TEST(ThresholdHysteresis, IsTheTemperaturePluginsModelInAnyUnit) {
  const std::string same = "band_margin = 0.5\nreading_min = -50\nreading_max = 150\ntrend_threshold_per_s = 0.005\n";
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {"plugin = \"temperature_hysteresis\"\nsettle_s = 1.5",
       "plugin = \"threshold_hysteresis\"\nsettle_s = 1.5\nunfold_below = 24\nfold_above = 27\n" + same},
      {std::string(kMetallic) + "\nresponse_s = 0.5",
       "plugin = \"threshold_hysteresis\"\nmode = \"latching\"\ntrigger = 37\nfolded_deg = 70\ntolerance_deg = "
       "8\nresponse_s = 0.5\n" + same}};
  for (const auto& [celsius, neutral] : pairs) {
    auto a = make_stimulus(celsius), b = make_stimulus(neutral);
    const std::vector<double> joints{-5, 12, 30, 61, 80};
    for (int i = 0; i < 120; ++i) {
      const double reading = 22 + 17 * std::sin(i / 15.0) + (i % 7) * 0.1;  // heats past 37, cools, heats
      a->update(reading, i / 10.0);
      b->update(reading, i / 10.0);
      ASSERT_EQ(a->state().feasible_min_deg, b->state().feasible_min_deg) << neutral << ", reading " << i;
      ASSERT_EQ(a->state().feasible_max_deg, b->state().feasible_max_deg) << neutral << ", reading " << i;
      ASSERT_EQ(a->fold_fraction(), b->fold_fraction()) << neutral << ", reading " << i;
      ASSERT_EQ(a->penalty(joints), b->penalty(joints)) << neutral << ", reading " << i;
      ASSERT_EQ(a->target_joint_deg(30), b->target_joint_deg(30)) << neutral << ", reading " << i;
    }
  }
}

// Its unit, label and reading range come from the table; the thresholds
// of the mode in use have no default.
TEST(ThresholdHysteresis, TakesItsUnitsFromTheTableAndNeedsItsThresholds) {
  auto s = make_stimulus(
      "plugin = \"threshold_hysteresis\"\nunfold_below = 5\nfold_above = 12\nreading_min = 0\nreading_max = 50\n"
      "label = \"B\"\nunit = \"mT\"");
  EXPECT_EQ(s->reading_label(), "B");
  EXPECT_EQ(s->reading_unit(), "mT");
  s->update(3, 0);
  EXPECT_DOUBLE_EQ(s->state().feasible_max_deg, 10);  // unfolded (0) within the 10 deg tolerance
  try {
    s->update(80, 1);
    ADD_FAILURE() << "a reading past reading_max was taken";
  } catch (const gtrack::InputError& e) {
    EXPECT_STREQ(e.what(), "a reading of 80, outside the 0 to 50 mT threshold_hysteresis takes: expected a reading "
                           "within reading_min and reading_max");
  }
  const auto error = [](const std::string& table) {
    try {
      make_stimulus(table);
    } catch (const gtrack::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("plugin = \"threshold_hysteresis\"\nunfold_below = 5").find("fold_above"), std::string::npos);
  EXPECT_NE(error("plugin = \"threshold_hysteresis\"\nmode = \"latching\"").find("trigger"), std::string::npos);
  EXPECT_NE(error("plugin = \"threshold_hysteresis\"\nunfold_below = 5\nfold_above = 12\nreading_min = 9\n"
                  "reading_max = 2")
                .find("reading_max"),
            std::string::npos);
  EXPECT_NE(error("plugin = \"threshold_hysteresis\"\nunfold_below = 5\nfold_above = 12\nfold_above_C = 3")
                .find("fold_above_C"),
            std::string::npos);  // a Celsius key is not one of its keys
}

}  // namespace

// A stimulus table whose reference joints differ from the gripper's is
// loaded, with a warning that names the file, the line and both values.
namespace {

std::string setup_warnings(const std::string& from, const std::string& to) {
  std::ifstream in(std::filesystem::path(GTRACK_TEST_SOURCE_DIR) / "configs" / "microscope_hydrogel.toml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find(from);
  if (at == std::string::npos) return "config line not found: " + from;
  text.replace(at, from.size(), to);
  return gtrack::testing::logged([&] { gtrack::load_setup(gtrack::ConfigTable::parse(text, "refs.toml"), {}); });
}

TEST(Setup, WarnsWhenTheStimulusReferenceJointsDifferFromTheGripper) {
  EXPECT_EQ(setup_warnings("folded_deg = 60.0", "folded_deg = 60.0"), "");
  const std::string w = setup_warnings("folded_deg = 60.0", "folded_deg = 55.0");
  EXPECT_NE(w.find("refs.toml:"), std::string::npos) << w;
  EXPECT_NE(w.find("stimulus.folded_deg"), std::string::npos) << w;
  EXPECT_NE(w.find("55 differs from the gripper's folded_deg = 60"), std::string::npos) << w;
}

}  // namespace
