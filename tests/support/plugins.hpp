// Loading the built-in plugins in tests, as the gtrack executable does.
#pragma once

#include <gtrack/config.hpp>
#include <gtrack/error.hpp>
#include <gtrack/plugin_loader.hpp>
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

}  // namespace gtrack::testing
