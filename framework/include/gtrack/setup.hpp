// A setup: the sensor, gripper and stimulus a config names, loaded as plugins.
//
// load_setup() reads the config file, builds the plugin search path
// (--plugin-path folders, then the config's plugin_path relative to the
// config file, then GTRACK_PLUGIN_PATH, then the default folder) and makes the
// three plugins from their tables. The engine's own tables are read by the
// engine (engine_config.hpp) and the root is checked for unknown tables
// once everything has been read.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "gtrack/config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/gripper.hpp"
#include "gtrack/plugin_loader.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/stimulus.hpp"

namespace gtrack {

struct Setup {
  ConfigTable root;
  std::filesystem::path config_file;
  std::shared_ptr<PluginLoader> loader;
  std::shared_ptr<Sensor> sensor;
  std::shared_ptr<Gripper> gripper;
  std::shared_ptr<Stimulus> stimulus;  // may be null when not asked for
  std::vector<std::filesystem::path> plugin_paths;  // SetupOptions::plugin_paths (the command line's)

  const ArticulatedModel& model() const { return gripper->model(); }
};

struct SetupOptions {
  std::vector<std::filesystem::path> plugin_paths;
  bool with_stimulus = true;
};

// The folders a config's plugin_path names, relative ones taken from the
// config's folder: searched after SetupOptions::plugin_paths.
GTRACK_API std::vector<std::filesystem::path> config_plugin_paths(const ConfigTable& root);

GTRACK_API Setup load_setup(const ConfigTable& root, const SetupOptions& options);
GTRACK_API Setup load_setup(const std::filesystem::path& config_file, const SetupOptions& options);

// The setup's plugin of `kind` as its errors name it: "gripper plugin
// 'name' (file)"; "gripper plugin" for one its loader did not make.
GTRACK_API std::string plugin_label(const Setup& setup, PluginKind kind);

}  // namespace gtrack
