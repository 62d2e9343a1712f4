// A stimulus plugin's results checked as they are used: a NaN penalty, a
// fold fraction outside [0, 1] or a feasible range upside down would
// otherwise pass into the search unnoticed (frames reported "ok" with no
// cost, joints clamped to a range whose ends are swapped).
#pragma once

#include <cmath>
#include <exception>
#include <memory>
#include <span>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "gtrack/error.hpp"
#include "gtrack/stimulus.hpp"

namespace gtrack::detail {

class CheckedStimulus final : public Stimulus {
 public:
  // `label` names the plugin in errors: "stimulus plugin 'name' (file)".
  CheckedStimulus(std::shared_ptr<Stimulus> plugin, std::string label)
      : plugin_(std::move(plugin)), label_(std::move(label)) {}

  // A refused reading (a std::exception) is the tracker's to report, with
  // its frame.
  void update(double value, double time_s) override {
    try {
      plugin_->update(value, time_s);
    } catch (const std::exception&) {
      throw;
    } catch (...) {
      throw PluginError(label_ + ": update() " + kNotStd);
    }
  }

  StimulusState state() const override {
    const StimulusState s = guarded("state()", [&] { return plugin_->state(); });
    if (std::isnan(s.feasible_min_deg) || std::isnan(s.feasible_max_deg) || !(s.feasible_min_deg <= s.feasible_max_deg)) {
      fail("state()", fmt::format("a feasible joint range of {} to {} deg", s.feasible_min_deg, s.feasible_max_deg),
           "feasible_min_deg <= feasible_max_deg, neither nan");
    }
    if (!std::isfinite(s.value) || !std::isfinite(s.rate)) {
      fail("state()", fmt::format("value {} and rate {}", s.value, s.rate), "finite numbers");
    }
    return s;
  }

  double penalty(std::span<const double> joints_deg) const override {
    const double p = guarded("penalty()", [&] { return plugin_->penalty(joints_deg); });
    if (!(p >= 0) || !std::isfinite(p)) fail("penalty()", fmt::format("{}", p), "a finite number, 0 or more");
    return p;
  }

  double fold_fraction() const override {
    const double f = guarded("fold_fraction()", [&] { return plugin_->fold_fraction(); });
    if (!(f >= 0 && f <= 1)) fail("fold_fraction()", fmt::format("{}", f), "a number in [0, 1]");
    return f;
  }

  double target_joint_deg(double current_deg) const override {
    const double q = guarded("target_joint_deg()", [&] { return plugin_->target_joint_deg(current_deg); });
    if (!std::isfinite(q)) fail("target_joint_deg()", fmt::format("{}", q), "a finite angle");
    return q;
  }

  std::string reading_label() const override { return plugin_->reading_label(); }
  std::string reading_unit() const override { return plugin_->reading_unit(); }

 private:
  [[noreturn]] void fail(const char* call, const std::string& got, const char* expected) const {
    throw PluginError(label_ + ": " + call + " returned " + got + "; expected " + expected);
  }

  // The plugin's own exception (not one of gtrack's, which say what they
  // are) as a PluginError naming the plugin and the call.
  template <class F>
  auto guarded(const char* call, F&& f) const -> decltype(f()) {
    try {
      return f();
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      throw PluginError(label_ + ": " + call + " threw: " + e.what());
    } catch (...) {
      throw PluginError(label_ + ": " + call + " " + kNotStd);
    }
  }

  static constexpr const char* kNotStd = "threw something that is not a std::exception (throw one, with a message)";

  std::shared_ptr<Stimulus> plugin_;
  std::string label_;
};

}  // namespace gtrack::detail
