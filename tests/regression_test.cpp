// Inputs found by the fuzz targets of fuzz/ that once misbehaved, kept as
// plain tests so the normal (g++) suite guards them too. Each test names its
// input in fuzz/crashes/ and says what went wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "gtrack/config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/stimulus_log.hpp"

namespace fs = std::filesystem;

namespace {

std::string crash_input(const std::string& name) {
  const fs::path p = fs::path(GTRACK_TEST_SOURCE_DIR) / "fuzz" / "crashes" / name;
  std::ifstream in(p, std::ios::binary);
  EXPECT_TRUE(in) << p;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The parse error, or "" when the text parsed.
std::string parse_error(const std::string& text) {
  try {
    (void)gtrack::ConfigTable::parse(text, "crash.toml");
  } catch (const gtrack::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// fuzz_config: a non-ASCII code point where TOML expects a bare key or table
// name (a typo like `[grippér]` or `fµ = 1`) makes TOML++ 3.3.0 (Debian 12)
// execute __builtin_unreachable() in is_non_ascii_horizontal_whitespace()
// (upstream marzer/tomlplusplus #190, fixed by #305). UBSan reports it in the
// clang fuzz build; what the user must get is a located one-line error.
TEST(Regression, NonAsciiInBareKeyIsAParseErrorNotUndefinedBehaviour) {
  for (const char* name : {"toml_unreachable_table_name.toml", "toml_unreachable_bare_key.toml"}) {
    const std::string e = parse_error(crash_input(name));
    EXPECT_EQ(e.rfind("crash.toml:", 0), 0u) << name << ": " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  const std::string e = parse_error(crash_input("toml_unreachable_fuzz_config"));
  EXPECT_EQ(e.rfind("crash.toml:1:", 0), 0u) << e;
}

// Non-ASCII text where TOML allows it (comments, strings) must keep working:
// units like µm and ° appear in lab configs.
TEST(Regression, NonAsciiInCommentsAndStringsIsAccepted) {
  const auto t = gtrack::ConfigTable::parse("# spread in \xC2\xB5m, angles in \xC2\xB0\nname = \"50 \xC2\xB5m\"\n",
                                            "ok.toml");
  EXPECT_EQ(t.string("name"), "50 \xC2\xB5m");
}

// fuzz_stimulus_log (fuzz/crashes/stimulus_interpolation_overflow.csv): two
// finite readings far apart (-1e308, 1e308) interpolate to +inf, because
// value_at() computes v0 + a * (v1 - v0) and v1 - v0 overflows. An infinite
// reading would reach the Stimulus plugin. Fixed in stimulus_log.cpp:
// (1 - a) * v0 + a * v1, which stays finite for finite rows and a in [0, 1].
// Since readings are bounded to a magnitude of 1e9, such a log is refused
// at the row that leaves the bound, and readings at the bound interpolate.
TEST(Regression, StimulusInterpolationStaysFinite) {
  const fs::path p = fs::path(GTRACK_TEST_SOURCE_DIR) / "fuzz" / "crashes" / "stimulus_interpolation_overflow.csv";
  try {
    gtrack::StimulusLog::load(p);
    FAIL() << "a reading of -1e308 must be refused";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stimulus_interpolation_overflow.csv:2: expected a reading of magnitude up "
                                         "to 1e9, got '-1e308'"),
              std::string::npos)
        << e.what();
  }
  const auto log = gtrack::StimulusLog::parse("frame,value\n0,-1e9\n2,1e9\n", "bound.csv");
  const auto v = log.value_at(1, 1 / 30.0);
  ASSERT_TRUE(v);
  EXPECT_DOUBLE_EQ(*v, 0.0);
}
