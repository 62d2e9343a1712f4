// Subcommands of the gtrack executable.
//
// Each subcommand lives in its own cmd_<name>.cpp and registers itself with
// GTRACK_COMMAND; main.cpp parses the common options (--plugin-path,
// --log-level, --version), picks the subcommand and turns every gtrack::Error
// into one line on stderr and exit code 1 (2 for a usage error).
#pragma once

#include <boost/program_options.hpp>
#include <gtrack/frame_source.hpp>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "gtrack/error.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/setup.hpp"

namespace gtrack::cli {

// The most frames a synthetic sequence has (synth, sweep, demo): nine hours
// at 30 frames/s; more is a typing slip, which would fill the memory and
// the disk before a word.
constexpr int kMaxSynthFrames = 1000000;

struct CommonOptions {
  std::vector<std::filesystem::path> plugin_paths;  // from --plugin-path, in order
  std::string log_level = "info";
  bool stdout_closed = false;  // the caller had closed stdout (`>&-`); it is /dev/null now
};

struct Command {
  std::string name;
  std::string summary;
  // Declares the subcommand's own options (common ones are added by main).
  std::function<void(boost::program_options::options_description&)> declare;
  // Runs with the parsed options; returns the process exit code.
  std::function<int(const CommonOptions&, const boost::program_options::variables_map&)> run;
  // Positional arguments, if the command takes any.
  std::vector<std::string> positional = {};
};

std::vector<Command>& registry();

struct Registrar {
  explicit Registrar(Command command) { registry().push_back(std::move(command)); }
};

// Thrown for a usage error (missing option, bad value); main prints the
// message and a hint to --help, and exits with 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// An output file's folder must exist before anything is computed: the
// error names the file, the folder, and (when given) the option.
inline void check_output_folder(const std::filesystem::path& file, const std::string& option = "") {
  const std::filesystem::path dir = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    const bool exists = std::filesystem::exists(dir, ec);
    throw gtrack::InputError(file.string() + ": '" + dir.string() + "' " +
                             (exists ? "is not a folder" : "does not exist") +
                             (option.empty() ? std::string() : " (--" + option + ")"));
  }
  if (std::filesystem::is_directory(file, ec)) {
    throw gtrack::InputError(file.string() + ": is a folder; expected a file name" +
                             (option.empty() ? std::string() : " (--" + option + ")"));
  }
}

// Named paths of a command's inputs or outputs, "--json" and its file.
using NamedPaths = std::vector<std::pair<std::string, std::filesystem::path>>;

// No output may be one of the command's inputs or another of its outputs
// (the same regular file by another name or link included): refused,
// naming both options, before anything is read or written.
inline void check_outputs_apart(const NamedPaths& outputs, const NamedPaths& inputs) {
  // Only a regular file is overwritten: /dev/null or /dev/stdout may be given twice.
  const auto same = [](const std::filesystem::path& a, const std::filesystem::path& b) {
    std::error_code ec;
    const bool a_there = std::filesystem::exists(a, ec), b_there = std::filesystem::exists(b, ec);
    if (a_there != b_there) return false;
    if (a_there) return std::filesystem::is_regular_file(a, ec) && std::filesystem::equivalent(a, b, ec);
    const auto ca = std::filesystem::weakly_canonical(a, ec);
    if (ec) return false;
    const auto cb = std::filesystem::weakly_canonical(b, ec);
    return !ec && ca == cb;
  };
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const auto& [option, file] = outputs[i];
    for (const auto& [input, in_file] : inputs) {
      if (same(file, in_file)) {
        throw UsageError(file.string() + ": is the " + input + " input; " + option + " would overwrite it");
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (same(file, outputs[j].second)) {
        throw UsageError(file.string() + ": given to both " + outputs[j].first + " and " + option +
                         "; expected two files");
      }
    }
  }
}

// --out, the folder a command writes into: an empty one would be the
// working folder, written over without a word.
inline std::filesystem::path out_folder(const boost::program_options::variables_map& vm) {
  const std::string out = vm["out"].as<std::string>();
  if (out.empty()) throw UsageError("--out is empty; expected a folder");
  return out;
}

// A folder to write into, made if missing: a path under a regular file or
// one that cannot be made is one line naming it.
inline void make_output_folder(const std::filesystem::path& dir, const std::string& option = "") {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw gtrack::InputError(dir.string() + ": cannot create the folder (" +
                             (ec ? ec.message() : std::string("a file of that name exists")) + ")" +
                             (option.empty() ? std::string() : " (--" + option + ")"));
  }
}

// --backend, when given, in place of the config's [render] backend.
inline void backend_option(const boost::program_options::variables_map& vm, std::string& backend) {
  if (!vm.count("backend")) return;
  const std::string b = vm["backend"].as<std::string>();
  if (b != "auto" && b != "gl" && b != "cpu") throw UsageError("--backend must be auto, gl or cpu");
  backend = b;
}

// --frames and --every (a command that declares both).
inline FrameRange frame_range_option(const boost::program_options::variables_map& vm) {
  FrameRange range;
  if (vm.count("frames")) {
    try {
      range = parse_frame_range(vm["frames"].as<std::string>());
    } catch (const InputError& e) {
      throw UsageError(e.what());  // an option, not an input: exit status 2, as the others
    }
  }
  range.every = vm["every"].as<int>();
  if (range.every < 1) throw UsageError("--every must be at least 1");
  return range;
}

// --seed: a whole number from 0 to 2^64 - 1. Read as text, because the
// option parser turns "-1" into 2^64 - 1 for an unsigned option.
inline std::uint64_t seed_option(const boost::program_options::variables_map& vm) {
  const std::string text = vm["seed"].as<std::string>();
  std::uint64_t seed = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), seed);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size()) {
    throw UsageError("--seed: expected a whole number of at least 0, got '" + text + "'");
  }
  return seed;
}

// A sensor that images a slab (an ultrasound slice: two clip planes facing
// each other across the viewing axis) has its "in-plane" error within the
// imaging plane and its "depth" error across it, not below the probe.
inline bool images_a_slab(const gtrack::Sensor& sensor) {
  return gtrack::slab_thickness_mm(sensor.projection()).has_value();
}

// The synthetic preset to draw a config's frames with (gtrack synth, gtrack
// sweep): --preset when given; for a --config without it, one whose frames
// that config can track. Warns when the preset's look is not one the
// config's [observation] bounds take. (app/synth_preset.cpp)
std::string synth_preset_for(const boost::program_options::variables_map& vm, const std::filesystem::path& config,
                             const gtrack::Setup& setup, const gtrack::ObservationConfig& bounds);

}  // namespace gtrack::cli

#define GTRACK_CLI_CONCAT2(a, b) a##b
#define GTRACK_CLI_CONCAT(a, b) GTRACK_CLI_CONCAT2(a, b)
#define GTRACK_COMMAND(...) \
  static ::gtrack::cli::Registrar GTRACK_CLI_CONCAT(gtrack_command_, __LINE__){::gtrack::cli::Command{__VA_ARGS__}};
