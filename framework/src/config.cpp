// ConfigTable: TOML++ kept inside the framework, key tracking, and errors
// that name file, line and key.
#include "gtrack/config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>
#include <toml++/toml.h>

#include "gtrack/error.hpp"
#include "gtrack/text_file.hpp"

namespace gtrack {

struct ConfigTable::Impl {
  std::shared_ptr<toml::table> root;  // keeps the document alive
  const toml::table* table = nullptr; // this table inside root (nullptr: empty)
  std::string source;
  std::string path;
  std::shared_ptr<std::set<std::string>> used = std::make_shared<std::set<std::string>>();
  int line = 0;  // where the table starts, for keys that are missing
  std::shared_ptr<const std::string> text;  // the document's text, as parsed
  std::filesystem::path base;  // where relative file paths start ("": the source's folder)
  // The files file_path() gave out, shared by every table of the document.
  std::shared_ptr<std::vector<NamedFile>> files = std::make_shared<std::vector<NamedFile>>();
};

namespace {

std::string describe_range(const Range& r) {
  std::ostringstream s;
  if (r.min && r.max) {
    s << "a number in " << (r.min_exclusive ? "(" : "[") << *r.min << ", " << *r.max << (r.max_exclusive ? ")" : "]");
  } else if (r.min) {
    s << "a number " << (r.min_exclusive ? "> " : ">= ") << *r.min;
  } else if (r.max) {
    s << "a number " << (r.max_exclusive ? "< " : "<= ") << *r.max;
  } else {
    s << "a number";
  }
  return s.str();
}

bool in_range(double v, const Range& r) {
  if (!std::isfinite(v)) return false;
  if (r.min && (r.min_exclusive ? v <= *r.min : v < *r.min)) return false;
  if (r.max && (r.max_exclusive ? v >= *r.max : v > *r.max)) return false;
  return true;
}

const char* type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    default: return "a date/time";
  }
}

std::optional<double> as_number(const toml::node& n) {
  if (auto v = n.value_exact<double>()) return *v;
  if (auto v = n.value_exact<int64_t>()) return static_cast<double>(*v);
  return std::nullopt;
}

size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t sub = prev[j - 1] + (std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                                               std::tolower(static_cast<unsigned char>(b[j - 1]))
                                           ? 0
                                           : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

}  // namespace

std::optional<std::string> closest_match(std::string_view word, const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  // Twice the edit distance, plus one when the first letter differs: of two
  // equally close candidates, the one that starts like the word wins
  // ('fxx' over 'cx' for 'fx'; a typo rarely hits the first letter).
  size_t best_score = 2 * (std::max<size_t>(2, word.size() / 3) + 1);
  for (const auto& c : candidates) {
    const size_t d = edit_distance(word, c);
    const size_t score = 2 * d + ((c.empty() || word.empty() || c[0] != word[0]) ? 1 : 0);
    if (score < best_score) {
      best_score = score;
      best = c;
    }
  }
  return best;
}

ConfigTable::ConfigTable() : impl_(std::make_shared<Impl>()) {}
ConfigTable::ConfigTable(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}
ConfigTable::~ConfigTable() = default;
ConfigTable::ConfigTable(const ConfigTable&) = default;
ConfigTable& ConfigTable::operator=(const ConfigTable&) = default;

ConfigTable ConfigTable::parse(std::string_view text, std::string source) {
  return parse(text, std::move(source), std::filesystem::path());
}

ConfigTable ConfigTable::parse(std::string_view text, std::string source, std::filesystem::path base_folder) {
  auto impl = std::make_shared<Impl>();
  try {
    impl->root = std::make_shared<toml::table>(toml::parse(text, source));
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << source << ":" << e.source().begin.line << ": " << e.description();
    // A bare word after '=' is read as the start of a boolean or a number.
    const std::string_view d = e.description();
    if (d.find("parsing boolean") != std::string_view::npos ||
        d.find("could not determine value type") != std::string_view::npos) {
      s << " (a text value needs quotes: key = \"text\")";
    }
    // A string that reaches the end of its line (or of the file) without
    // its closing quote: said so, instead of the parser's complaint about
    // the line break it met.
    if (d.find("string") != std::string_view::npos) {
      size_t at = 0;
      for (auto line = e.source().begin.line; line > 1 && at != std::string_view::npos; --line) {
        at = text.find('\n', at);
        if (at != std::string_view::npos) ++at;
      }
      const size_t col = e.source().begin.column > 0 ? e.source().begin.column - 1 : 0;
      if (at != std::string_view::npos) {
        const size_t end = std::min(text.find('\n', at), text.size());
        if (at + col >= end || text[at + col] == '\r' || text[at + col] == '\n') {
          s.str("");
          s << source << ":" << e.source().begin.line << ": unterminated string (expected its closing quote before "
            << "the end of the line)";
        }
      }
    }
    throw ConfigError(s.str());
  }
  impl->table = impl->root.get();
  impl->source = std::move(source);
  impl->line = 1;
  impl->text = std::make_shared<const std::string>(text);
  impl->base = std::move(base_folder);
  return ConfigTable(impl);
}

std::string ConfigTable::file_text(const std::string& path) {
  // A config is text of a few kilobytes: a device or a pipe that never ends
  // (/dev/zero, a wrong path into a data folder) is stopped, not read into memory.
  try {
    return read_text_file(path, std::size_t(16) << 20, "a TOML config file");
  } catch (const InputError& e) {
    throw ConfigError(e.what());
  }
}

ConfigTable ConfigTable::load_file(const std::string& path) { return parse(file_text(path), path); }

const std::string& ConfigTable::source() const { return impl_->source; }
const std::string& ConfigTable::path() const { return impl_->path; }

std::string ConfigTable::toml_text() const {
  if (impl_->text && impl_->table == impl_->root.get()) return *impl_->text;
  std::ostringstream s;
  if (impl_->table) s << *impl_->table << "\n";
  return s.str();
}

namespace {

// A value as a message shows it: numbers with up to 15 digits (0.4, not
// toml++'s 0.40000000000000002), arrays and inline tables written out.
void write_value(std::ostream& s, const toml::node& n) {
  if (const auto x = as_number(n)) {
    char b[32];
    std::snprintf(b, sizeof b, "%.15g", *x);
    s << b;
  } else if (const toml::array* a = n.as_array()) {
    s << "[";
    for (size_t i = 0; i < a->size(); ++i) {
      s << (i ? ", " : "");
      write_value(s, *a->get(i));
    }
    s << "]";
  } else if (const toml::table* t = n.as_table()) {
    s << "{";
    const char* sep = " ";
    for (auto&& [k, v] : *t) {
      s << sep << k.str() << " = ";
      write_value(s, v);
      sep = ", ";
    }
    s << " }";
  } else {
    n.visit([&s](auto&& v) { s << v; });
  }
}

std::string value_text(const toml::node& n) {
  if (n.is_table()) return "a table";
  std::ostringstream s;
  write_value(s, n);
  return shown(s.str(), 80);
}

// Keys of both tables, in the first's file order, then the second's.
std::vector<std::string> keys_of_both(const toml::table& a, const toml::table& b) {
  std::vector<std::pair<std::pair<int, int>, std::string>> ks;
  for (auto&& [k, v] : a) ks.push_back({{0, static_cast<int>(v.source().begin.line)}, std::string(k.str())});
  for (auto&& [k, v] : b) {
    if (!a.contains(k.str())) ks.push_back({{1, static_cast<int>(v.source().begin.line)}, std::string(k.str())});
  }
  std::stable_sort(ks.begin(), ks.end());
  std::vector<std::string> out;
  for (auto& [at, k] : ks) out.push_back(std::move(k));
  return out;
}

std::optional<ConfigDifference> table_difference(const toml::table& a, const toml::table& b, const std::string& path);

bool same_value(const toml::node& a, const toml::node& b) {
  // Integers exactly (beyond 2^53 a double cannot tell them apart), an
  // integer and a float by value, nan as itself.
  if (a.is_integer() && b.is_integer()) return *a.value_exact<int64_t>() == *b.value_exact<int64_t>();
  const auto x = as_number(a), y = as_number(b);
  if (x || y) return x && y && (*x == *y || (std::isnan(*x) && std::isnan(*y)));
  if (a.type() != b.type()) return false;
  if (const toml::table* t = a.as_table()) return !table_difference(*t, *b.as_table(), "");
  if (const toml::array* u = a.as_array()) {
    const toml::array& v = *b.as_array();
    if (u->size() != v.size()) return false;
    for (size_t i = 0; i < u->size(); ++i) {
      if (!same_value(*u->get(i), *v.get(i))) return false;
    }
    return true;
  }
  std::ostringstream x_text, y_text;  // whole, where value_text cuts a long one short
  write_value(x_text, a);
  write_value(y_text, b);
  return x_text.str() == y_text.str();
}

std::optional<ConfigDifference> table_difference(const toml::table& a, const toml::table& b, const std::string& path) {
  for (const std::string& k : keys_of_both(a, b)) {
    const toml::node* x = a.get(k);
    const toml::node* y = b.get(k);
    if (x && y && x->is_table() && y->is_table()) {
      if (auto d = table_difference(*x->as_table(), *y->as_table(), path.empty() ? k : path + "." + k)) return d;
      continue;
    }
    if (x && y && same_value(*x, *y)) continue;
    return ConfigDifference{(path.empty() ? "" : "[" + path + "] ") + shown(k, 60),
                            x ? value_text(*x) : "not set", y ? value_text(*y) : "not set"};
  }
  return std::nullopt;
}

}  // namespace

std::optional<ConfigDifference> first_difference(const ConfigTable& first, const ConfigTable& second) {
  static const toml::table empty;
  const toml::table* a = first.impl_->table;
  const toml::table* b = second.impl_->table;
  return table_difference(a ? *a : empty, b ? *b : empty, first.path());
}

namespace {
// "file:line: key 'path.key'": where a config error is, as every message starts.
std::string located(const ConfigTable::Impl& impl, int line, std::string_view key) {
  std::ostringstream s;
  s << (impl.source.empty() ? std::string("<config>") : impl.source);
  if (line > 0) s << ":" << line;
  s << ": ";
  std::string full = impl.path.empty() ? std::string(key) : impl.path + "." + std::string(key);
  s << "key '" << shown(full, 60) << "'";
  return s.str();
}

// An error in one element of an array: its own line, and its index written as
// a key path writes an array table's ("distortion[1]", counted from 0).
[[noreturn]] void fail_element(const ConfigTable::Impl& impl, std::string_view key, const std::string& index,
                               const toml::node& element, const std::string& message) {
  int line = static_cast<int>(element.source().begin.line);
  if (line <= 0) line = impl.line;
  throw ConfigError(located(impl, line, std::string(key) + index) + ": " + message);
}

std::string index(size_t i) { return "[" + std::to_string(i) + "]"; }
}  // namespace

std::string ConfigTable::where(std::string_view key) const {
  int line = impl_->line;
  if (impl_->table) {
    if (auto* n = impl_->table->get(key)) line = static_cast<int>(n->source().begin.line);
  }
  return located(*impl_, line, key);
}

void ConfigTable::fail(std::string_view key, std::string_view message) const {
  throw ConfigError(where(key) + ": " + std::string(message));
}

bool ConfigTable::has(std::string_view key) const {
  return impl_->table && impl_->table->contains(key);
}

std::vector<std::string> ConfigTable::keys() const {
  std::vector<std::pair<int, std::string>> ks;
  if (impl_->table) {
    for (auto&& [k, v] : *impl_->table) ks.emplace_back(static_cast<int>(v.source().begin.line), std::string(k.str()));
  }
  std::stable_sort(ks.begin(), ks.end());
  std::vector<std::string> out;
  for (auto& [l, k] : ks) out.push_back(k);
  return out;
}

void ConfigTable::mark_used(std::string_view key) const { impl_->used->insert(std::string(key)); }

namespace {
// "missing; expected X", plus the likely misspelling when the table has an
// unread key close to the one asked for.
std::string missing_message(const ConfigTable& table, std::string_view key, const std::string& expected) {
  return "missing; " + expected + table.misspelling_hint(key);
}

const toml::node* lookup(const ConfigTable::Impl& impl, std::string_view key) {
  impl.used->insert(std::string(key));
  return impl.table ? impl.table->get(key) : nullptr;
}
}  // namespace

double ConfigTable::number(std::string_view key, Range range) const {
  const toml::node* n = lookup(*impl_, key);
  if (!n) fail(key, missing_message(*this, key, "expected " + describe_range(range)));
  auto v = as_number(*n);
  if (!v) fail(key, std::string("expected ") + describe_range(range) + ", got " + type_name(*n));
  if (!in_range(*v, range)) {
    std::ostringstream s;
    s << "value " << *v << " is out of range; expected " << describe_range(range);
    fail(key, s.str());
  }
  return *v;
}

double ConfigTable::number_or(std::string_view key, double fallback, Range range) const {
  if (!has(key)) {
    mark_used(key);
    return fallback;
  }
  return number(key, range);
}

long long ConfigTable::integer(std::string_view key, Range range) const {
  const toml::node* n = lookup(*impl_, key);
  if (!n) fail(key, missing_message(*this, key, "expected an integer"));
  auto v = n->value_exact<int64_t>();
  if (!v) fail(key, std::string("expected an integer, got ") + type_name(*n));
  if (!in_range(static_cast<double>(*v), range)) {
    std::ostringstream s;
    s << "value " << *v << " is out of range; expected an integer" << describe_range(range).substr(8);
    fail(key, s.str());
  }
  return *v;
}

long long ConfigTable::integer_or(std::string_view key, long long fallback, Range range) const {
  if (!has(key)) {
    mark_used(key);
    return fallback;
  }
  return integer(key, range);
}

bool ConfigTable::boolean_or(std::string_view key, bool fallback) const {
  const toml::node* n = lookup(*impl_, key);
  if (!n) return fallback;
  auto v = n->value_exact<bool>();
  if (!v) fail(key, std::string("expected true or false, got ") + type_name(*n));
  return *v;
}

std::string ConfigTable::string(std::string_view key) const {
  const toml::node* n = lookup(*impl_, key);
  if (!n) fail(key, missing_message(*this, key, "expected a string"));
  auto v = n->value_exact<std::string>();
  if (!v) fail(key, std::string("expected a string, got ") + type_name(*n));
  return *v;
}

std::string ConfigTable::string_or(std::string_view key, std::string fallback) const {
  if (!has(key)) {
    mark_used(key);
    return fallback;
  }
  return string(key);
}

std::filesystem::path ConfigTable::file_path(std::string_view key) const {
  std::filesystem::path file = string(key);
  if (file.is_relative()) file = base_folder() / file;
  auto& files = *impl_->files;
  const auto known = std::find_if(files.begin(), files.end(),
                                  [&](const NamedFile& f) { return f.table == impl_->path && f.key == key; });
  if (known == files.end()) {
    files.push_back({impl_->path, std::string(key), file});
  } else {
    known->path = file;
  }
  return file;
}

std::vector<NamedFile> ConfigTable::named_files() const { return *impl_->files; }

std::filesystem::path ConfigTable::base_folder() const {
  if (!impl_->base.empty()) return impl_->base;
  if (impl_->source.empty() || impl_->source.front() == '<') return {};
  return std::filesystem::path(impl_->source).parent_path();
}

std::string ConfigTable::choice_or(std::string_view key, std::string fallback,
                                   const std::vector<std::string>& allowed) const {
  std::string v = string_or(key, std::move(fallback));
  if (std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + ("\"" + a + "\"");
    std::string msg = "unknown value \"" + shown(v, 60) + "\"; expected one of " + list;
    if (auto m = closest_match(v, allowed)) msg += " (did you mean \"" + *m + "\"?)";
    fail(key, msg);
  }
  return v;
}

std::vector<double> ConfigTable::numbers(std::string_view key, std::optional<size_t> size, Range range) const {
  const toml::node* n = lookup(*impl_, key);
  std::string expected = size ? "an array of " + std::to_string(*size) + " numbers" : std::string("an array of numbers");
  if (!n) fail(key, missing_message(*this, key, "expected " + expected));
  const toml::array* arr = n->as_array();
  if (!arr) fail(key, "expected " + expected + ", got " + type_name(*n));
  if (size && arr->size() != *size) {
    fail(key, "expected " + expected + ", got " + std::to_string(arr->size()));
  }
  std::vector<double> out;
  for (size_t i = 0; i < arr->size(); ++i) {
    auto v = as_number(*arr->get(i));
    if (!v) fail_element(*impl_, key, index(i), *arr->get(i), std::string("expected a number, got ") + type_name(*arr->get(i)));
    if (!in_range(*v, range)) {
      std::ostringstream s;
      s << "value " << *v << " is out of range; expected " << describe_range(range);
      fail_element(*impl_, key, index(i), *arr->get(i), s.str());
    }
    out.push_back(*v);
  }
  return out;
}

std::vector<double> ConfigTable::numbers_or(std::string_view key, std::vector<double> fallback,
                                            std::optional<size_t> size, Range range) const {
  if (!has(key)) {
    mark_used(key);
    return fallback;
  }
  return numbers(key, size, range);
}

std::vector<std::vector<double>> ConfigTable::number_rows(std::string_view key, size_t row_size, Range range) const {
  const toml::node* n = lookup(*impl_, key);
  const std::string expected = "an array of [" + std::to_string(row_size) + " numbers] arrays";
  if (!n) fail(key, missing_message(*this, key, "expected " + expected));
  const toml::array* arr = n->as_array();
  if (!arr) fail(key, "expected " + expected + ", got " + type_name(*n));
  std::vector<std::vector<double>> out;
  for (size_t i = 0; i < arr->size(); ++i) {
    const toml::array* row = arr->get(i)->as_array();
    if (!row || row->size() != row_size) {
      fail_element(*impl_, key, index(i), *arr->get(i), "expected an array of " + std::to_string(row_size) + " numbers");
    }
    std::vector<double> r;
    for (size_t j = 0; j < row->size(); ++j) {
      auto v = as_number(*row->get(j));
      if (!v || !in_range(*v, range)) {
        fail_element(*impl_, key, index(i) + index(j), *row->get(j), "expected " + describe_range(range));
      }
      r.push_back(*v);
    }
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<std::string> ConfigTable::strings_or(std::string_view key, std::vector<std::string> fallback) const {
  const toml::node* n = lookup(*impl_, key);
  if (!n) return fallback;
  const toml::array* arr = n->as_array();
  if (!arr) fail(key, std::string("expected an array of strings, got ") + type_name(*n));
  std::vector<std::string> out;
  for (size_t i = 0; i < arr->size(); ++i) {
    auto v = arr->get(i)->value_exact<std::string>();
    if (!v) fail_element(*impl_, key, index(i), *arr->get(i), "expected a string");
    out.push_back(*v);
  }
  return out;
}

std::string ConfigTable::misspelling_hint(std::string_view key) const {
  if (!impl_->table) return {};
  // Two-letter keys come in families one letter apart (fx, fy, cx, cy): an
  // unread one of the same length is more likely a key still to be read
  // than a typo.
  std::vector<std::string> unread;
  for (auto&& [k, v] : *impl_->table) {
    const std::string_view name = k.str();
    const bool sibling = key.size() <= 2 && name.size() == key.size();
    if (!impl_->used->count(std::string(name)) && name != key && !sibling) unread.emplace_back(name);
  }
  const auto m = closest_match(key, unread);
  if (!m) return {};
  const toml::node* n = impl_->table->get(*m);
  return " (is '" + *m + "' on line " + std::to_string(n ? n->source().begin.line : 0) + " a misspelling of it?)";
}

ConfigTable ConfigTable::table(std::string_view key) const {
  const toml::node* n = lookup(*impl_, key);
  auto impl = std::make_shared<Impl>();
  impl->root = impl_->root;
  impl->source = impl_->source;
  impl->base = impl_->base;
  impl->files = impl_->files;
  impl->path = impl_->path.empty() ? std::string(key) : impl_->path + "." + std::string(key);
  impl->line = impl_->line;
  if (n) {
    const toml::table* t = n->as_table();
    if (!t) fail(key, std::string("expected a table, got ") + type_name(*n));
    impl->table = t;
    impl->line = static_cast<int>(t->source().begin.line);
  }
  return ConfigTable(impl);
}

std::vector<ConfigTable> ConfigTable::tables(std::string_view key) const {
  const toml::node* n = lookup(*impl_, key);
  std::vector<ConfigTable> out;
  if (!n) return out;
  const toml::array* arr = n->as_array();
  if (!arr) fail(key, std::string("expected an array of tables, got ") + type_name(*n));
  for (size_t i = 0; i < arr->size(); ++i) {
    const toml::table* t = arr->get(i)->as_table();
    if (!t) fail_element(*impl_, key, index(i), *arr->get(i), "expected a table");
    auto impl = std::make_shared<Impl>();
    impl->root = impl_->root;
    impl->source = impl_->source;
    impl->base = impl_->base;
    impl->files = impl_->files;
    impl->path = (impl_->path.empty() ? std::string(key) : impl_->path + "." + std::string(key)) + "[" +
                 std::to_string(i) + "]";
    impl->table = t;
    impl->line = static_cast<int>(t->source().begin.line);
    out.push_back(ConfigTable(impl));
  }
  return out;
}

void ConfigTable::check_all_used() const {
  if (!impl_->table) return;
  std::vector<std::string> known(impl_->used->begin(), impl_->used->end());
  for (const auto& k : keys()) {
    if (impl_->used->count(k)) continue;
    std::string msg = "unknown key";
    if (impl_->path.empty()) msg += " at the top level";
    else msg += " in [" + impl_->path + "]";
    if (auto m = closest_match(k, known)) msg += " (did you mean '" + *m + "'?)";
    else if (!known.empty()) {
      std::string list;
      for (const auto& a : known) list += (list.empty() ? "" : ", ") + a;
      msg += "; known keys: " + list;
    }
    fail(k, msg);
  }
}

}  // namespace gtrack
