// Configuration as it crosses the plugin boundary.
//
// A TOML config is parsed once by the framework (TOML++ stays inside the
// framework library). Each table is handed out as a ConfigTable, a framework
// type, so that plugins never compile a second copy of the parser. A
// ConfigTable remembers which keys were read; after a plugin's factory has
// returned, the loader calls check_all_used(), so an unknown or misspelled key
// is always an error "file:line: [table] unknown key 'fxx' (did you mean
// 'fx'?)". Every getter that fails throws ConfigError with file, line and key.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gtrack/export.hpp"

namespace gtrack {

// Bounds accepted by a numeric key; unset means unbounded.
struct Range {
  std::optional<double> min;
  std::optional<double> max;
  bool min_exclusive = false;
  bool max_exclusive = false;

  static Range positive() { return {0.0, std::nullopt, true, false}; }
  static Range non_negative() { return {0.0, std::nullopt, false, false}; }
  static Range closed(double lo, double hi) { return {lo, hi, false, false}; }
};

class ConfigTable;

// A file a config names, as file_path() resolved it: the table's dotted
// path ("" at the top level), the key, and the path. A run keeps them with
// its config, so that --resume can tell when one of them has changed.
struct NamedFile {
  std::string table;
  std::string key;
  std::filesystem::path path;
  // "[table] key", or "key" at the top level, as messages name keys.
  std::string name() const { return table.empty() ? key : "[" + table + "] " + key; }
  // "table.key", as a TOML path.
  std::string dotted() const { return table.empty() ? key : table + "." + key; }
};

// Where two configs differ: the first key (in file order) whose value is
// not the same in both, as "[table] key" ("key" at the top level), and its
// value in each ("not set" where it is missing). Numbers compare by value
// (32 and 32.0 are the same); comments and the order of keys do not count.
struct ConfigDifference {
  std::string key;
  std::string first;
  std::string second;
};
GTRACK_API std::optional<ConfigDifference> first_difference(const ConfigTable& first, const ConfigTable& second);

class GTRACK_API ConfigTable {
 public:
  // An empty table that belongs to no file (for defaults and tests).
  ConfigTable();
  ~ConfigTable();
  ConfigTable(const ConfigTable&);
  ConfigTable& operator=(const ConfigTable&);

  // Parses TOML text; `source` names it in errors (a file path or "<string>").
  static ConfigTable parse(std::string_view toml_text, std::string source = "<string>");
  // The same; relative file paths in it are taken from `base_folder`
  // instead of the folder of `source`.
  static ConfigTable parse(std::string_view toml_text, std::string source, std::filesystem::path base_folder);
  // Reads and parses a file. Throws ConfigError naming the file and line.
  static ConfigTable load_file(const std::string& path);
  // A config file's text, read once (a pipe too). Throws ConfigError naming
  // the file when it is a folder or cannot be read.
  static std::string file_text(const std::string& path);

  bool has(std::string_view key) const;
  // Keys present in this table, in file order.
  std::vector<std::string> keys() const;

  double number(std::string_view key, Range range = {}) const;
  double number_or(std::string_view key, double fallback, Range range = {}) const;
  long long integer(std::string_view key, Range range = {}) const;
  long long integer_or(std::string_view key, long long fallback, Range range = {}) const;
  bool boolean_or(std::string_view key, bool fallback) const;
  std::string string(std::string_view key) const;
  std::string string_or(std::string_view key, std::string fallback) const;
  // A string naming a file; a relative path is taken from the folder of the
  // config file this table came from (as it stands without one). Each path
  // given out is recorded for named_files().
  std::filesystem::path file_path(std::string_view key) const;
  // The files file_path() gave out so far, from any table of this document,
  // in the order asked (a key asked twice is listed once).
  std::vector<NamedFile> named_files() const;
  // Where relative file paths start: the folder given to parse() or
  // its own overload of parse(), else the folder of the source ("" without one).
  std::filesystem::path base_folder() const;
  // A string that must be one of `allowed`; the error lists them.
  std::string choice_or(std::string_view key, std::string fallback,
                        const std::vector<std::string>& allowed) const;
  // An array of numbers; `size` (if set) is the exact length required.
  std::vector<double> numbers(std::string_view key, std::optional<size_t> size = {},
                              Range range = {}) const;
  std::vector<double> numbers_or(std::string_view key, std::vector<double> fallback,
                                 std::optional<size_t> size = {}, Range range = {}) const;
  // An array of arrays of numbers, each of `row_size` values ([[x, y], ...]).
  std::vector<std::vector<double>> number_rows(std::string_view key, size_t row_size, Range range = {}) const;
  std::vector<std::string> strings_or(std::string_view key, std::vector<std::string> fallback) const;

  // A sub-table; a missing key gives an empty table that still reports its path.
  ConfigTable table(std::string_view key) const;
  // An array of tables ([[key]]).
  std::vector<ConfigTable> tables(std::string_view key) const;

  // Marks a key as read without reading it (for keys handled elsewhere).
  void mark_used(std::string_view key) const;
  // Throws ConfigError for the first key that nothing read, with a suggestion
  // for a likely misspelling among the keys that were read.
  void check_all_used() const;

  // For a key that is missing: " (is 'k2' on line N a misspelling of it?)"
  // when the table has a key nothing read that is close to it, else "".
  std::string misspelling_hint(std::string_view key) const;

  // "file:line: [path] key 'k'": where a key is, for messages of callers.
  std::string where(std::string_view key) const;
  // The file this table came from ("" if none).
  const std::string& source() const;
  // Dotted path of this table inside its file ("" for the root).
  const std::string& path() const;
  // The table as TOML: for the root of a parsed document, the text it was
  // parsed from, comments included; otherwise its keys written out.
  std::string toml_text() const;

  // Throws ConfigError "file:line: [path] key 'k': <message>".
  [[noreturn]] void fail(std::string_view key, std::string_view message) const;

  struct Impl;

 private:
  friend std::optional<ConfigDifference> first_difference(const ConfigTable&, const ConfigTable&);
  explicit ConfigTable(std::shared_ptr<Impl> impl);
  std::shared_ptr<Impl> impl_;
};

// The closest candidate to `word` by edit distance, if it is close enough to be
// a likely misspelling.
GTRACK_API std::optional<std::string> closest_match(std::string_view word,
                                                    const std::vector<std::string>& candidates);

}  // namespace gtrack
