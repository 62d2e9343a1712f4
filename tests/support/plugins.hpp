// Loading the built-in plugins in tests, as the gtrack executable does.
#pragma once

#include <gtrack/config.hpp>
#include <gtrack/error.hpp>
#include <gtrack/plugin_loader.hpp>
#include <gtrack/setup.hpp>
#include <memory>
#include <string>

namespace gtrack::testing {

// The loader with the build tree's plugin folder (the default search path).
inline PluginLoader& loader() {
  static PluginLoader l;
  return l;
}

// Makes a plugin from TOML text of its table, e.g. "plugin = \"hydrogel_six_finger\"".
inline std::shared_ptr<Gripper> make_gripper(const std::string& toml) {
  return loader().make_gripper(ConfigTable::parse(toml, "<test>"));
}
inline std::shared_ptr<Sensor> make_sensor(const std::string& toml) {
  return loader().make_sensor(ConfigTable::parse(toml, "<test>"));
}
inline std::shared_ptr<Stimulus> make_stimulus(const std::string& toml) {
  return loader().make_stimulus(ConfigTable::parse(toml, "<test>"));
}

// The hydrogel gripper seen by an ultrasound probe, upright or turned by
// `rotation` ("[rx, ry, rz]", deg), with `engine` (engine tables) added.
inline Setup probe_setup(const std::string& rotation = "", const std::string& engine = "") {
  std::string text = "[sensor]\nplugin = \"ultrasound_slice\"\n";
  if (!rotation.empty()) text += "probe_rotation_deg = " + rotation + "\n";
  text += "[gripper]\nplugin = \"hydrogel_six_finger\"\n[stimulus]\nplugin = \"temperature_hysteresis\"\n" + engine;
  return load_setup(ConfigTable::parse(text, "<test>"), {});
}

// A small microscope: 256x256, the 4 mm hydrogel gripper ~128 px across at
// 100 mm, rendered at scale 0.5 on the cpu backend, searched within 3 mm.
inline constexpr char kSmallMicroscopeConfig[] = R"(
[sensor]
plugin = "pinhole_microscope"
width = 256
height = 256
fx = 3200.0
working_distance_mm = 100.0
[gripper]
plugin = "hydrogel_six_finger"
[stimulus]
plugin = "temperature_hysteresis"
[render]
backend = "cpu"
scale = 0.5
threads = 2
[search]
position_min_mm = [-3.0, -3.0, 98.0]
position_max_mm = [3.0, 3.0, 102.0]
)";

// That microscope's setup, with `extra` (TOML) added.
inline Setup small_microscope_setup(const std::string& extra = "") {
  return load_setup(ConfigTable::parse(std::string(kSmallMicroscopeConfig) + extra, "<test>"), {});
}

}  // namespace gtrack::testing
