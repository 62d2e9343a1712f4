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

}  // namespace gtrack::testing
