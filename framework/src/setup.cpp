// Loading the three plugins a config names.
#include "gtrack/setup.hpp"

#include "gtrack/error.hpp"

namespace gtrack {

namespace fs = std::filesystem;

Setup load_setup(const ConfigTable& root, const SetupOptions& options) {
  Setup s;
  s.root = root;
  s.config_file = root.source();
  s.plugin_paths = options.plugin_paths;
  auto loader = std::make_shared<PluginLoader>(options.plugin_paths);
  const fs::path base = s.config_file.has_parent_path() ? s.config_file.parent_path() : fs::path(".");
  for (const auto& p : root.strings_or("plugin_path", {})) {
    fs::path dir(p);
    loader->add_path(dir.is_absolute() ? dir : base / dir);
  }
  s.loader = loader;
  for (const char* t : {"sensor", "gripper"}) {
    if (!root.has(t)) {
      root.fail(t, std::string("missing table [") + t + "]; it must name a " + t + " plugin" + root.misspelling_hint(t));
    }
  }
  s.sensor = loader->make_sensor(root.table("sensor"));
  s.gripper = loader->make_gripper(root.table("gripper"));
  if (options.with_stimulus) {
    if (!root.has("stimulus")) {
      root.fail("stimulus", "missing table [stimulus]; it must name a stimulus plugin" + root.misspelling_hint("stimulus"));
    }
    s.stimulus = loader->make_stimulus(root.table("stimulus"));
  } else {
    root.mark_used("stimulus");
  }
  return s;
}

Setup load_setup(const fs::path& config_file, const SetupOptions& options) {
  return load_setup(ConfigTable::load_file(config_file.string()), options);
}

}  // namespace gtrack
