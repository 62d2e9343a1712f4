// Fuzz target: a TOML config as the framework reads it.
//
// Parses the input with ConfigTable::parse, then walks every table and asks
// every key for every type (number, integer, string, arrays, tables), the way
// plugins and the engine do, and finally checks for unused keys. The only
// acceptable failure is gtrack::Error (a located one-line message); anything
// else escaping, a crash or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "gtrack/config.hpp"
#include "gtrack/error.hpp"
#include "toml_known_bugs.hpp"

namespace {

template <class F>
void expect_error_or_value(F&& f) {
  try {
    f();
  } catch (const gtrack::Error&) {
  }
}

void walk(const gtrack::ConfigTable& t, int depth) {
  // Deeply nested documents are legal TOML; 8 levels cover every real config.
  if (depth > 8) return;
  const auto keys = t.keys();
  for (const auto& k : keys) {
    expect_error_or_value([&] { (void)t.where(k); });
    expect_error_or_value([&] { (void)t.number(k); });
    expect_error_or_value([&] { (void)t.number(k, gtrack::Range::positive()); });
    expect_error_or_value([&] { (void)t.number_or(k, 1.0, gtrack::Range::closed(-1, 1)); });
    expect_error_or_value([&] { (void)t.integer(k, gtrack::Range{1, 64}); });
    expect_error_or_value([&] { (void)t.integer_or(k, 3); });
    expect_error_or_value([&] { (void)t.boolean_or(k, false); });
    expect_error_or_value([&] { (void)t.string(k); });
    expect_error_or_value([&] { (void)t.choice_or(k, "cpu", {"auto", "cpu", "gl"}); });
    expect_error_or_value([&] { (void)t.numbers(k); });
    expect_error_or_value([&] { (void)t.numbers(k, size_t{3}, gtrack::Range::non_negative()); });
    expect_error_or_value([&] { (void)t.number_rows(k, 2); });
    expect_error_or_value([&] { (void)t.strings_or(k, {}); });
    expect_error_or_value([&] { walk(t.table(k), depth + 1); });
    expect_error_or_value([&] {
      for (const auto& sub : t.tables(k)) walk(sub, depth + 1);
    });
  }
  // A key that is absent: the "missing" message looks for a misspelling.
  expect_error_or_value([&] { (void)t.number("fx"); });
  expect_error_or_value([&] { (void)t.table("sensor").string("plugin"); });
  expect_error_or_value([&] { t.check_all_used(); });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (gtrack_fuzz::has_toml_unreachable_code_point(text)) return 0;
  try {
    const auto root = gtrack::ConfigTable::parse(text, "fuzz.toml");
    // A fresh table per pass: check_all_used() sees only what this pass read.
    gtrack::ConfigTable fresh = gtrack::ConfigTable::parse(text, "fuzz.toml");
    expect_error_or_value([&] { fresh.check_all_used(); });
    walk(root, 0);
  } catch (const gtrack::Error&) {
  }
  return 0;
}
