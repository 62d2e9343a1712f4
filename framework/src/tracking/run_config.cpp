// run_config.toml: writing a run's copy of its config, and checking a
// resumed run's config and files against it.
#include "run_config.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gtrack/error.hpp"
#include "gtrack/text_file.hpp"
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

// `path` made absolute and normal (as it is when that fails).
fs::path absolute_normal(const fs::path& path) {
  std::error_code ec;
  const fs::path p = fs::absolute(path, ec);
  return ec ? path : p.lexically_normal();
}

// A path in a message: absolute, control bytes escaped.
std::string displayed(const fs::path& path) { return shown(absolute_normal(path).string(), 1 << 12); }

// A path on a header line: absolute, in ASCII, every byte readable back
// (a backslash doubled; control bytes and bytes above 0x7F as \xNN), so
// that the copy stays valid UTF-8 whatever the folder's name.
std::string encoded(const fs::path& path) {
  std::string out;
  for (const char ch : absolute_normal(path).string()) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\\') {
      out += "\\\\";
    } else if (c < 0x20 || c >= 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out;
}

// The path encoded() wrote; nullopt for text it cannot have written.
std::optional<fs::path> decoded(std::string_view text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\\') {
      out += text[i];
    } else if (i + 1 < text.size() && text[i + 1] == '\\') {
      out += '\\';
      ++i;
    } else if (i + 3 < text.size() && text[i + 1] == 'x' && std::isxdigit(static_cast<unsigned char>(text[i + 2])) &&
               std::isxdigit(static_cast<unsigned char>(text[i + 3]))) {
      out += static_cast<char>(std::stoi(std::string(text.substr(i + 2, 2)), nullptr, 16));
      i += 3;
    } else {
      return std::nullopt;
    }
  }
  return fs::path(out);
}

// FNV-1a 64 of `in`'s bytes, at most `limit` of them; `size` is how many
// were read. False when the stream failed.
bool hash_bytes(std::istream& in, std::uint64_t limit, std::uint64_t& hash, std::uint64_t& size) {
  hash = 0xcbf29ce484222325ull;
  size = 0;
  std::vector<char> block(1 << 16);
  while (in && size < limit) {
    in.read(block.data(), static_cast<std::streamsize>(std::min<std::uint64_t>(block.size(), limit - size)));
    const auto n = static_cast<size_t>(in.gcount());
    for (size_t i = 0; i < n; ++i) {
      hash ^= static_cast<unsigned char>(block[i]);
      hash *= 0x100000001b3ull;
    }
    size += n;
  }
  return !in.bad();
}

// "812 bytes, FNV-1a 64 0123456789abcdef", or "missing" / "unreadable".
std::string fingerprint(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return "missing";
  std::ifstream in(path, std::ios::binary);
  if (!in) return "unreadable";
  std::uint64_t hash = 0, size = 0;
  if (!hash_bytes(in, UINT64_MAX, hash, size)) return "unreadable";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%llu bytes, FNV-1a 64 %016llx", static_cast<unsigned long long>(size),
                static_cast<unsigned long long>(hash));
  return buf;
}

// The size of `kept` (a fingerprint) when the file at `path` is longer and
// starts with exactly the bytes it names: a file that has only grown.
std::optional<std::uint64_t> grown_from(const fs::path& path, const std::string& kept) {
  unsigned long long size = 0, hash = 0;
  int end = 0;
  if (std::sscanf(kept.c_str(), "%llu bytes, FNV-1a 64 %16llx%n", &size, &hash, &end) != 2 ||
      static_cast<size_t>(end) != kept.size()) {
    return std::nullopt;
  }
  std::error_code ec;
  const auto now = fs::file_size(path, ec);
  if (ec || now <= size) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  std::uint64_t h = 0, n = 0;
  if (!in || !hash_bytes(in, size, h, n) || n != size || h != hash) return std::nullopt;
  return size;
}

// The comment lines a text starts with (at most 10,000), without their line ends.
std::vector<std::string> header_lines(std::string_view text) {
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.remove_prefix(3);  // an editor's byte-order mark
  std::vector<std::string> lines;
  size_t at = 0;
  while (at < text.size() && text.compare(at, 2, "# ") == 0 && lines.size() < 10000) {
    const size_t end = std::min(text.find('\n', at), text.size());
    std::string line(text.substr(at, end - at));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
    at = end + 1;
  }
  return lines;
}

// The header lines of a file (read only as far as they go).
std::vector<std::string> file_header_lines(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string text, line;
  // As far as the header goes, within a config's size.
  for (int n = 1; read_bounded_line(in, line, std::size_t(16) << 20, file.string(), n, "a TOML config") &&
                  (line.rfind("# ", 0) == 0 || (text.empty() && line.rfind("\xEF\xBB\xBF# ", 0) == 0)) &&
                  text.size() < (16u << 20);
       ++n) {
    text += line + "\n";
  }
  return header_lines(std::string_view(text));
}

// The files a run's copy lists: those the config names, then `used`.
std::vector<NamedFile> listed_files(const ConfigTable& root, const std::vector<NamedFile>& used) {
  std::vector<NamedFile> files = root.named_files();
  files.insert(files.end(), used.begin(), used.end());
  return files;
}

struct KeptFile {
  std::string key, path, fingerprint;
};

std::vector<KeptFile> kept_files(const fs::path& file) {
  std::vector<KeptFile> files;
  for (const std::string& line : file_header_lines(file)) {
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
  const std::vector<std::string> lines = file_header_lines(file);
  return !lines.empty() && lines.front().rfind(kFirstLine, 0) == 0;
}

std::optional<fs::path> run_config_base_folder(std::string_view text) {
  const std::vector<std::string> lines = header_lines(text);
  if (lines.empty() || lines.front().rfind(kFirstLine, 0) != 0) return std::nullopt;
  for (const std::string& line : lines) {
    if (line.rfind(kBaseLine, 0) == 0) return decoded(std::string_view(line).substr(kBaseLine.size()));
  }
  // A copy by an earlier release: the folder of the file it was read from
  // (shown as it was, control bytes escaped: such a name is not taken).
  if (lines.size() > 1 && lines[1].rfind(kEarlierSecondLine, 0) == 0) {
    const size_t from = lines[0].find(kFromMark);
    if (from == std::string::npos) return std::nullopt;
    const std::string file = lines[0].substr(from + kFromMark.size());
    if (file.empty() || file.front() == '<' || file.find('\\') != std::string::npos) return std::nullopt;
    return fs::path(file).parent_path();
  }
  return std::nullopt;
}

ConfigTable load_config(const fs::path& file) {
  const std::string text = ConfigTable::file_text(file.string());
  std::error_code ec;
  fs::path base = run_config_base_folder(text).value_or(fs::path());
  if (base.empty() && !fs::is_regular_file(file, ec)) base = fs::current_path(ec);
  return ConfigTable::parse(text, file.string(), base);
}

void write_run_config(const fs::path& file, const ConfigTable& root, bool durable, const std::vector<NamedFile>& used) {
  std::string from = root.source();
  from = from.empty() ? std::string("<config>") : from.front() == '<' ? shown(from, 1 << 12, true) : encoded(from);
  // A run's own copy given as the config is copied without its header; a
  // byte-order mark goes, or it would stand inside the new header.
  std::string text = root.toml_text();
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
  const auto drop_first_line = [&text] { text.erase(0, std::min(text.find('\n'), text.size() - 1) + 1); };
  while (text.rfind(kPrefix, 0) == 0) drop_first_line();
  if (text.rfind(kEarlierSecondLine, 0) == 0) drop_first_line();

  // Relative paths in a config without a folder of its own (a path
  // without one, a string) were taken from the working folder.
  fs::path base = root.base_folder();
  if (base.empty()) {
    std::error_code ec;
    base = fs::current_path(ec);
  }
  std::string header = std::string(kFirstLine) + std::string(kFromMark) + from + "\n";
  header += std::string(kBaseLine) + encoded(base) + "\n";
  for (const NamedFile& f : listed_files(root, used)) {
    header += std::string(kFileLine) + f.name() + " = " + encoded(f.path) + ": " + fingerprint(f.path) + "\n";
  }
  header += std::string(kPrefix) + "--resume checks that this config, and the files listed, are unchanged\n";
  replace_file(file, header + text, durable);
}

std::map<std::string, std::uint64_t> check_same_config(const fs::path& file, const ConfigTable& root,
                                                       const std::vector<NamedFile>& used,
                                                       const std::vector<std::string>& may_grow) {
  std::map<std::string, std::uint64_t> grown;
  std::error_code ec;
  if (!fs::exists(file, ec)) return grown;
  if (fs::is_regular_file(file, ec) && fs::file_size(file, ec) == 0) {
    throw InputError(shown(file.string(), 1 << 12) +
                     ": is empty (cut short, as a power loss can leave it without --durable); cannot resume "
                     "(run without --resume, or with another --out)");
  }
  std::optional<ConfigDifference> d;
  try {
    d = first_difference(ConfigTable::load_file(file.string()), root);
  } catch (const Error& e) {
    throw InputError(std::string(e.what()) + "; cannot resume (this is the config of the run being resumed)");
  }
  const std::string now = root.source().empty() ? std::string("this config") : shown(root.source(), 1 << 12);
  const std::string copy = shown(file.string(), 1 << 12);
  if (d) {
    throw InputError(copy + ": " + d->key + " was " + d->first + " in the run being resumed, is " +
                     d->second + " in " + now +
                     "; cannot resume with another config (give the config the run was started with, which this "
                     "file copies and names, or another --out)");
  }
  const std::vector<NamedFile> current = listed_files(root, used);
  for (const KeptFile& kept : kept_files(file)) {
    const auto it = std::find_if(current.begin(), current.end(), [&](const NamedFile& f) { return f.name() == kept.key; });
    if (it == current.end()) continue;
    const std::string path = encoded(it->path);
    // The same file by another name (a symbolic link, a bind mount) is the same.
    const std::optional<fs::path> kept_path = decoded(kept.path);
    std::error_code ec;
    // (Messages show the paths as the user gave them.)
    const std::string kept_shown = kept_path ? displayed(*kept_path) : kept.path;
    const std::string path_shown = displayed(it->path);
    if (path != kept.path && !(kept_path && fs::equivalent(*kept_path, it->path, ec))) {
      throw InputError(copy + ": " + kept.key + " was the file " + kept_shown +
                       " in the run being resumed, is " + path_shown + " with " + now +
                       "; cannot resume with another file (give the files of the run being resumed, or another --out)");
    }
    if (const std::string print = fingerprint(it->path); print != kept.fingerprint) {
      if (std::find(may_grow.begin(), may_grow.end(), kept.key) != may_grow.end()) {
        if (const auto size = grown_from(it->path, kept.fingerprint)) {
          grown[kept.key] = *size;
          continue;
        }
      }
      throw InputError(path_shown + ": has changed since the run being resumed began (" + kept.key + ": it was " +
                       kept.fingerprint + ", is " + print +
                       "); cannot resume with another file (restore it, or choose another --out)");
    }
  }
  return grown;
}

}  // namespace gtrack::detail
