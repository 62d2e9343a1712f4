// sequence.toml: the input config, made to track a synthetic sequence as is.
//
// The input is re-emitted table by table through TOML++ (comments are not
// kept; the plugin tables' values are). Relative plugin folders and files
// (keys ending in "_file") are made absolute, because the sequence folder is
// usually elsewhere; folders given on the command line are written first. The frame rate
// is the sequence's, so that stimulus rates mean the same as when planned.
// A configured initial pose is dropped: it described some other scene, and
// the sequence must be tracked from the coarse search like a new recording.
#include <cctype>
#include <charconv>
#include <filesystem>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>
#include <toml++/toml.h>

#include "../tracking/run_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/synth.hpp"
#include "gtrack/text_file.hpp"

namespace gtrack {

namespace {

// Relative paths in keys ending in "_file" (a gripper's model_file), at any
// depth of a plugin table, made absolute against the input config's folder.
void absolute_files(toml::table& table, const std::filesystem::path& base) {
  for (auto&& [key, node] : table) {
    if (auto* sub = node.as_table()) {
      absolute_files(*sub, base);
    } else if (auto* s = node.as_string(); s && key.str().ends_with("_file")) {
      const std::filesystem::path p(s->get());
      if (!p.empty() && p.is_relative()) *s = (base / p).lexically_normal().string();
    }
  }
}

// TOML++ as built prints a float with 17 significant digits (0.09 as
// 0.089999999999999997). Each float outside a string is written again as
// the shortest text that reads back as the same double.
std::string shortest_floats(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  char quote = 0;
  for (size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (quote) {
      out += c;
      if (c == '\\' && quote == '"' && i + 1 < text.size()) {
        out += text[++i];
      } else if (c == quote) {
        quote = 0;
      }
      ++i;
      continue;
    }
    if (c == '\'' || c == '"') quote = c;
    const bool starts_value = i == 0 || std::string_view(" =[,\n").find(text[i - 1]) != std::string_view::npos;
    if (starts_value && (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+')) {
      size_t end = i + 1;
      while (end < text.size() && (std::isalnum(static_cast<unsigned char>(text[end])) ||
                                   std::string_view(".+-_").find(text[end]) != std::string_view::npos))
        ++end;
      const std::string_view token = text.substr(i, end - i);
      double value = 0;
      const char* first = token.data() + (token.front() == '+');
      const auto [ptr, ec] = std::from_chars(first, token.data() + token.size(), value);
      char buf[32];
      const auto written = std::to_chars(buf, buf + sizeof buf, value);
      if (token.find_first_of(".eE") != std::string_view::npos && ec == std::errc() &&
          ptr == token.data() + token.size() && written.ec == std::errc()) {
        std::string shorter(buf, written.ptr);
        if (shorter.find_first_of(".e") == std::string::npos) shorter += ".0";
        out += shorter.size() < token.size() ? shorter : std::string(token);
      } else {
        out += token;
      }
      i = end;
      continue;
    }
    out += c;
    ++i;
  }
  return out;
}

}  // namespace

void write_sequence_config(const std::filesystem::path& input_config, const SynthPlan& plan,
                           const std::filesystem::path& out_file, const std::vector<std::filesystem::path>& plugin_paths) {
  write_sequence_config(detail::load_config(input_config), plan, out_file, plugin_paths);
}

void write_sequence_config(const ConfigTable& config, const SynthPlan& plan, const std::filesystem::path& out_file,
                           const std::vector<std::filesystem::path>& plugin_paths) {
  namespace fs = std::filesystem;
  // The text the setup was read from: a config given as a pipe is not read again.
  toml::table root;
  try {
    root = toml::parse(config.toml_text(), config.source());
  } catch (const toml::parse_error& e) {
    throw ConfigError(config.source() + ": " + std::string(e.description()));
  }
  const fs::path base = config.base_folder().empty() ? fs::current_path() : fs::absolute(config.base_folder());
  toml::array abs;
  for (const fs::path& dir : plugin_paths) abs.push_back(fs::absolute(dir).lexically_normal().string());
  if (auto* paths = root["plugin_path"].as_array()) {
    for (auto& p : *paths) {
      if (auto s = p.value<std::string>()) {
        const fs::path dir(*s);
        abs.push_back((dir.is_absolute() ? dir : (base / dir).lexically_normal()).string());
      }
    }
  }
  if (!abs.empty()) root.insert_or_assign("plugin_path", std::move(abs));
  for (const char* t : {"sensor", "gripper", "stimulus"}) {
    if (auto* table = root[t].as_table()) absolute_files(*table, base);
  }
  // The files the plugins read.
  for (const NamedFile& f : config.named_files()) {
    if (auto* s = root.at_path(f.dotted()).as_string()) {
      *s = fs::absolute(f.path).lexically_normal().string();
    } else {
      logger().warn("{}: {} names a file that sequence.toml keeps as it was (a key that cannot be found by its "
                    "dotted path); if it is relative, track the sequence from the config's folder",
                    config.source(), f.name());
    }
  }
  if (!root["tracker"].as_table()) root.insert_or_assign("tracker", toml::table{});
  toml::table& tracker = *root["tracker"].as_table();
  tracker.insert_or_assign("fps", plan.preset.frame_rate_hz);
  tracker.erase("initial_pose");

  std::ostringstream out;
  out << "# gtrack: config for tracking the synthetic sequence in this folder.\n"
      << "#   gtrack track --config sequence.toml --input frames --stimulus stimulus.csv --out track\n"
      << "# Made by 'gtrack synth' from " << shown(config.source().empty() || config.source().front() == '<'
                                                       ? config.source()
                                                       : fs::absolute(config.source()).string(),
                                                   1 << 12)
      << "\n"
      << "# (preset '" << plan.preset.name << "', seed " << plan.options.seed << ", " << plan.frames.size()
      << " frames";
  if (plan.options.occlusion_scale != 1) out << ", occlusion scale " << plan.options.occlusion_scale;
  out << "). Holds no ground truth: tracking starts from the coarse search.\n\n";
  std::ostringstream body;
  body << root << "\n";
  out << shortest_floats(body.str());
  write_text_file(out_file, out.str());
}

}  // namespace gtrack
