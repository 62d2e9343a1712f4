// run_config.toml: writing a run's copy of its config, and checking a
// resumed run's config and files against it.
#include "run_config.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "gtrack/error.hpp"
#include "replace_file.hpp"

namespace gtrack::detail {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view kPrefix = "# gtrack track: ";
constexpr std::string_view kFirstLine = "# gtrack track: the config of the run in this folder";
constexpr std::string_view kFromMark = ", as read from ";
constexpr std::string_view kBaseLine = "# gtrack track: its relative paths start at ";
constexpr std::string_view kFileLine = "# gtrack track: file ";
// The second line of copies written by earlier releases, whose relative
// paths start at the folder of the file named on the first line.
constexpr std::string_view kEarlierSecondLine = "# (relative paths in it are taken from";

std::string absolute_text(const fs::path& path) {
  std::error_code ec;
  const fs::path p = fs::absolute(path, ec);
  return shown((ec ? path : p.lexically_normal()).string(), 1 << 12);
}

// "812 bytes, FNV-1a 64 0123456789abcdef", or "missing" / "unreadable".
std::string fingerprint(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return "missing";
  std::ifstream in(path, std::ios::binary);
  if (!in) return "unreadable";
  std::uint64_t hash = 0xcbf29ce484222325ull;
  std::uint64_t size = 0;
  std::vector<char> block(1 << 16);
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const auto n = static_cast<size_t>(in.gcount());
    for (size_t i = 0; i < n; ++i) {
      hash ^= static_cast<unsigned char>(block[i]);
      hash *= 0x100000001b3ull;
    }
    size += n;
  }
  if (in.bad()) return "unreadable";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%llu bytes, FNV-1a 64 %016llx", static_cast<unsigned long long>(size),
                static_cast<unsigned long long>(hash));
  return buf;
}

std::vector<std::string> header_lines(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line) && line.rfind("# ", 0) == 0 && lines.size() < 10000) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
  }
  return lines;
}

struct KeptFile {
  std::string key, path, fingerprint;
};

std::vector<KeptFile> kept_files(const fs::path& file) {
  std::vector<KeptFile> files;
  for (const std::string& line : header_lines(file)) {
    if (line.rfind(kFileLine, 0) != 0) continue;
    const std::string rest = line.substr(kFileLine.size());
    const size_t eq = rest.find(" = ");
    const size_t colon = rest.rfind(": ");
    if (eq == std::string::npos || colon == std::string::npos || colon < eq) continue;
    files.push_back({rest.substr(0, eq), rest.substr(eq + 3, colon - eq - 3), rest.substr(colon + 2)});
  }
  return files;
}

}  // namespace

bool written_by_a_run(const fs::path& file) {
  const std::vector<std::string> lines = header_lines(file);
  return !lines.empty() && lines.front().rfind(kFirstLine, 0) == 0;
}

std::optional<fs::path> run_config_base_folder(const fs::path& file) {
  const std::vector<std::string> lines = header_lines(file);
  if (lines.empty() || lines.front().rfind(kFirstLine, 0) != 0) return std::nullopt;
  std::string folder;
  for (const std::string& line : lines) {
    if (line.rfind(kBaseLine, 0) == 0) folder = line.substr(kBaseLine.size());
  }
  if (folder.empty() && lines.size() > 1 && lines[1].rfind(kEarlierSecondLine, 0) == 0) {
    const size_t from = lines[0].find(kFromMark);
    if (from != std::string::npos) folder = fs::path(lines[0].substr(from + kFromMark.size())).parent_path().string();
  }
  // A name shown with escapes ("\x0A") is not the folder's own.
  if (folder.empty() || folder.front() == '<' || folder.find('\\') != std::string::npos) return std::nullopt;
  return fs::path(folder);
}

void write_run_config(const fs::path& file, const ConfigTable& root) {
  std::string from = root.source();
  if (!from.empty() && from.front() != '<') from = absolute_text(from);
  // A run's own copy given as the config is copied without its header; a
  // byte-order mark goes, or it would stand inside the new header.
  std::string text = root.toml_text();
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
  const auto drop_first_line = [&text] { text.erase(0, std::min(text.find('\n'), text.size() - 1) + 1); };
  while (text.rfind(kPrefix, 0) == 0) drop_first_line();
  if (text.rfind(kEarlierSecondLine, 0) == 0) drop_first_line();

  std::string header = std::string(kFirstLine) + std::string(kFromMark) + (from.empty() ? "<config>" : from) + "\n";
  if (const fs::path base = root.base_folder(); !base.empty()) {
    header += std::string(kBaseLine) + absolute_text(base) + "\n";
  }
  for (const NamedFile& f : root.named_files()) {
    header += std::string(kFileLine) + f.key + " = " + absolute_text(f.path) + ": " + fingerprint(f.path) + "\n";
  }
  header += std::string(kPrefix) + "--resume checks that this config, and the files it names, are unchanged\n";
  replace_file(file, header + text);
}

void check_same_config(const fs::path& file, const ConfigTable& root) {
  std::error_code ec;
  if (!fs::exists(file, ec)) return;
  std::optional<ConfigDifference> d;
  try {
    d = first_difference(ConfigTable::load_file(file.string()), root);
  } catch (const Error& e) {
    throw InputError(std::string(e.what()) + "; cannot resume (this is the interrupted run's config)");
  }
  const std::string now = root.source().empty() ? std::string("this config") : root.source();
  if (d) {
    throw InputError(file.string() + ": " + d->key + " was " + d->first + " in the interrupted run, is " +
                     d->second + " in " + now +
                     "; cannot resume with another config (give the config the run was started with, which this "
                     "file copies and names, or another --out)");
  }
  const std::vector<NamedFile> current = root.named_files();
  for (const KeptFile& kept : kept_files(file)) {
    const auto it = std::find_if(current.begin(), current.end(), [&](const NamedFile& f) { return f.key == kept.key; });
    if (it == current.end()) continue;
    const std::string path = absolute_text(it->path);
    if (path != kept.path) {
      throw InputError(file.string() + ": " + kept.key + " was the file " + kept.path +
                       " in the interrupted run, is " + path + " with " + now +
                       "; cannot resume with another file (give a config in the first one's folder, or another --out)");
    }
    if (const std::string print = fingerprint(it->path); print != kept.fingerprint) {
      throw InputError(path + ": has changed since the interrupted run began (" + kept.key + ": it was " +
                       kept.fingerprint + ", is " + print +
                       "); cannot resume with another file (restore it, or choose another --out)");
    }
  }
}

}  // namespace gtrack::detail
