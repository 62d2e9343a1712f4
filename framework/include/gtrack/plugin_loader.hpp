// Finding, checking and loading plugins.
//
// Search order (first match wins): the directories given by the user
// (--plugin-path, then the config's plugin_path), then GTRACK_PLUGIN_PATH
// (colon-separated), then the plugin folder of the build tree or install
// prefix that holds libgtrack itself (default_plugin_dir()). A plugin named `foo` lives in
// libgtrack_foo.so. Each way of failing has its own one-line PluginError:
// not found (the paths searched and the plugins of that kind that exist),
// not a gtrack plugin, ABI mismatch (both versions), wrong kind, factory threw
// (its message), unknown config key.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "gtrack/config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/plugin.hpp"

namespace gtrack {

struct PluginRecord {
  PluginKind kind;
  std::string name;
  std::string version;
  std::string summary;
  std::filesystem::path file;
};

// A plugin as errors name it: "gripper plugin 'name' (file)".
GTRACK_API std::string plugin_label(PluginKind kind, const std::string& name, const std::filesystem::path& file);

class GTRACK_API PluginLoader {
 public:
  // `user_paths` come first in the search order, then GTRACK_PLUGIN_PATH,
  // then default_plugin_dir().
  explicit PluginLoader(std::vector<std::filesystem::path> user_paths = {});

  // Appends a user path (after the earlier ones, before GTRACK_PLUGIN_PATH);
  // used for the config's plugin_path.
  void add_path(const std::filesystem::path& dir);
  // The directories searched, in order (existing or not).
  const std::vector<std::filesystem::path>& search_paths() const { return paths_; }

  // Every valid plugin found (first of each name wins); libraries that fail a
  // check are skipped with a warning in the log.
  std::vector<PluginRecord> discover() const;
  // The other files of `taken`'s name in the folders searched after its own
  // (the same file found again is none): the plugins it sets aside.
  std::vector<std::filesystem::path> set_aside_by(const std::filesystem::path& taken) const;

  // Loads the plugin named by table["plugin"], checks it, constructs it from
  // the table and checks that every key of the table was read. The instance
  // keeps its library loaded for as long as it lives. A stimulus comes
  // wrapped so that its results are checked as they are used (a NaN
  // penalty, a range upside down: PluginError naming it).
  std::shared_ptr<Sensor> make_sensor(const ConfigTable& table) const;
  std::shared_ptr<Gripper> make_gripper(const ConfigTable& table) const;
  std::shared_ptr<Stimulus> make_stimulus(const ConfigTable& table) const;

  // Same, from an explicit library file (used for tests and diagnostics).
  template <class Interface>
  std::shared_ptr<Interface> make_from_file(const std::filesystem::path& file, const std::string& name,
                                            const ConfigTable& table) const;

  // The plugins this loader has made, in order, each once (the file it was
  // loaded from): what a run records of the code that made its results.
  std::vector<PluginRecord> loaded() const;

  // Reads and checks a library's PluginInfo without calling into it.
  // Throws PluginError on any mismatch.
  static PluginRecord inspect(const std::filesystem::path& file);

 private:
  template <class Interface>
  std::shared_ptr<Interface> make(const ConfigTable& table) const;
  std::filesystem::path find(PluginKind kind, const std::string& name) const;
  void rebuild();

  std::vector<std::filesystem::path> initial_user_;
  std::vector<std::filesystem::path> user_;
  std::vector<std::filesystem::path> env_paths_;
  std::vector<std::filesystem::path> paths_;
  std::shared_ptr<std::vector<PluginRecord>> loaded_ = std::make_shared<std::vector<PluginRecord>>();
};

// The file of the framework library itself (libgtrack.so).
GTRACK_API std::filesystem::path framework_library_file();

// The directory that holds the running executable.
GTRACK_API std::filesystem::path executable_dir();
// The folders of the build tree or install prefix: <prefix>/lib/gtrack/plugins
// and <prefix>/share/gtrack, found from the executable's location.
GTRACK_API std::filesystem::path default_plugin_dir();
GTRACK_API std::filesystem::path data_dir();

}  // namespace gtrack
