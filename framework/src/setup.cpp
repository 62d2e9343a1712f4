// Loading the three plugins a config names.
#include "gtrack/setup.hpp"

#include <cmath>
#include <utility>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "tracking/run_config.hpp"

namespace gtrack {

namespace fs = std::filesystem;

namespace {

// The stimulus's reference joint values, where its table gives them, describe
// the same open and folded shapes as the gripper's: a difference makes S(H)
// pull the joints away from the shapes the coarse search and the fallback use.
void warn_on_reference_mismatch(const ConfigTable& stimulus, const GripperGeometry& g) {
  const std::pair<const char*, double> refs[] = {{"unfolded_deg", g.unfolded_deg}, {"folded_deg", g.folded_deg}};
  for (const auto& [key, gripper_value] : refs) {
    if (!stimulus.has(key)) continue;
    double v = 0;
    try {
      v = stimulus.number(key);
    } catch (const ConfigError&) {
      continue;  // not a number: the plugin's own reading of it decides
    }
    if (std::abs(v - gripper_value) > 1e-9) {
      logger().warn("{}: {} differs from the gripper's {} = {}; both describe the same shape and should agree",
                    stimulus.where(key), v, key, gripper_value);
    }
  }
}

}  // namespace

Setup load_setup(const ConfigTable& root, const SetupOptions& options) {
  Setup s;
  s.root = root;
  s.config_file = root.source();
  s.plugin_paths = options.plugin_paths;
  auto loader = std::make_shared<PluginLoader>(options.plugin_paths);
  const fs::path base = root.base_folder().empty() ? fs::path(".") : root.base_folder();
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
    warn_on_reference_mismatch(root.table("stimulus"), s.model().geometry());
  } else {
    root.mark_used("stimulus");
  }
  return s;
}

Setup load_setup(const fs::path& config_file, const SetupOptions& options) {
  // A run's copy of its config takes its relative paths from where the
  // original's were taken; a pipe's are taken from the working folder.
  return load_setup(detail::load_config(config_file), options);
}

}  // namespace gtrack
