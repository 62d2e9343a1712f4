// run_config.toml: the config a run was made with, kept beside its results,
// with the files it names. It says what made the results, and what a
// resumed run must go on with.
//
// The copy is the config's text as read, under a header of comment lines
// that each start "# gtrack track: ": where the config was read from, the
// folder its relative paths are taken from, and each file it names with its
// size and FNV-1a hash. Given back as a config, the copy's relative paths
// are taken from that folder, as the original's were.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gtrack/config.hpp"

namespace gtrack::detail {

inline constexpr const char* kRunConfigName = "run_config.toml";

// `file` starts with the header of a run's copy (a file of the user's own
// under that name is never replaced).
bool written_by_a_run(const std::filesystem::path& file);

// For the text of a run's copy: the folder its relative paths are taken
// from. nullopt for any other text, or a copy that names no folder.
std::optional<std::filesystem::path> run_config_base_folder(std::string_view text);

// A config file, read once (it may be a pipe). Its relative paths start at
// the folder a run's copy names, at the working folder for a pipe, else at
// the file's own folder.
ConfigTable load_config(const std::filesystem::path& file);

// Writes the copy of `root` (a copy given as the config is copied without
// its header) with the files root.named_files() lists, and `used`: the
// other files the run's results come from (the stimulus log, the plugins'
// libraries), each under a name of its own.
void write_run_config(const std::filesystem::path& file, const ConfigTable& root, bool durable = false,
                      const std::vector<NamedFile>& used = {});

// Throws InputError, naming the first difference, when `root` is not the
// config kept in `file`, or a file it names or one of `used` has changed.
// A run without the copy (from an earlier release) is not checked, nor a
// file the copy does not list. A file whose name `may_grow` lists may have
// grown, its first bytes those the copy names: returned, by name, with the
// number of bytes the run read.
std::map<std::string, std::uint64_t> check_same_config(const std::filesystem::path& file, const ConfigTable& root,
                                                       const std::vector<NamedFile>& used = {},
                                                       const std::vector<std::string>& may_grow = {});

}  // namespace gtrack::detail
