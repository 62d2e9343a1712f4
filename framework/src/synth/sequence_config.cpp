// sequence.toml: the input config, made to track a synthetic sequence as is.
//
// The input is re-emitted table by table through TOML++ (comments are not
// kept; the plugin tables' values are). Relative plugin folders are made
// absolute, because the sequence folder is usually elsewhere. The frame rate
// is the sequence's, so that stimulus rates mean the same as when planned.
// A configured initial pose is dropped: it described some other scene, and
// the sequence must be tracked from the coarse search like a new recording.
#include <filesystem>
#include <fstream>
#include <toml++/toml.h>

#include "gtrack/error.hpp"
#include "gtrack/synth.hpp"

namespace gtrack {

void write_sequence_config(const std::filesystem::path& input_config, const SynthPlan& plan,
                           const std::filesystem::path& out_file) {
  namespace fs = std::filesystem;
  toml::table root;
  try {
    root = toml::parse_file(input_config.string());
  } catch (const toml::parse_error& e) {
    throw ConfigError(input_config.string() + ": " + std::string(e.description()));
  }
  const fs::path base = fs::absolute(input_config).parent_path();
  if (auto* paths = root["plugin_path"].as_array()) {
    toml::array abs;
    for (auto& p : *paths) {
      if (auto s = p.value<std::string>()) {
        const fs::path dir(*s);
        abs.push_back((dir.is_absolute() ? dir : (base / dir).lexically_normal()).string());
      }
    }
    root.insert_or_assign("plugin_path", std::move(abs));
  }
  if (!root["tracker"].as_table()) root.insert_or_assign("tracker", toml::table{});
  toml::table& tracker = *root["tracker"].as_table();
  tracker.insert_or_assign("fps", plan.preset.frame_rate_hz);
  tracker.erase("initial_pose");

  std::ofstream out(out_file);
  if (!out) throw InputError(out_file.string() + ": cannot write");
  out << "# gtrack: config for tracking the synthetic sequence in this folder.\n"
      << "#   gtrack track --config sequence.toml --input frames --stimulus stimulus.csv --out track\n"
      << "# Made by 'gtrack synth' from " << fs::absolute(input_config).string() << "\n"
      << "# (preset '" << plan.preset.name << "', seed " << plan.options.seed << ", " << plan.frames.size()
      << " frames";
  if (plan.options.occlusion_scale != 1) out << ", occlusion scale " << plan.options.occlusion_scale;
  out << "). Holds no ground truth: tracking starts from the coarse search.\n\n" << root << "\n";
  if (!out) throw InputError(out_file.string() + ": write failed");
}

}  // namespace gtrack
