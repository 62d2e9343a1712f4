// Config errors name the file, the line and the key, and suggest a fix.
#include <gtest/gtest.h>

#include <gtrack/config.hpp>
#include <gtrack/error.hpp>

#include "support/plugins.hpp"

namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const gtrack::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, MisspelledKeyNamesFileLineKeyAndSuggestion) {
  auto root = gtrack::ConfigTable::parse("[sensor]\nplugin = \"pinhole_microscope\"\nwidth = 64\nheight = 64\nfxx = 100\n",
                                         "cfg.toml");
  std::string e = error_of([&] { gtrack::testing::loader().make_sensor(root.table("sensor")); });
  // fx is missing, so the plugin itself complains first; with fx present the misspelling is caught.
  EXPECT_NE(e.find("cfg.toml"), std::string::npos) << e;
  auto root2 = gtrack::ConfigTable::parse(
      "[sensor]\nplugin = \"pinhole_microscope\"\nwidth = 64\nheight = 64\nfx = 100\nworking_distanse_mm = 50\n",
      "cfg.toml");
  e = error_of([&] { gtrack::testing::loader().make_sensor(root2.table("sensor")); });
  EXPECT_NE(e.find("cfg.toml:6:"), std::string::npos) << e;
  EXPECT_NE(e.find("sensor.working_distanse_mm"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'working_distance_mm'"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);
}

TEST(Config, WrongTypeAndRange) {
  auto t = gtrack::ConfigTable::parse("a = \"x\"\nb = -1\nc = [1, \"two\"]\n", "f.toml");
  std::string e = error_of([&] { t.number("a"); });
  EXPECT_NE(e.find("f.toml:1: key 'a': expected a number, got a string"), std::string::npos) << e;
  e = error_of([&] { t.number("b", gtrack::Range::positive()); });
  EXPECT_NE(e.find("f.toml:2: key 'b'"), std::string::npos) << e;
  EXPECT_NE(e.find("> 0"), std::string::npos) << e;
  e = error_of([&] { t.numbers("c"); });
  EXPECT_NE(e.find("f.toml:3: key 'c[1]': expected a number, got a string"), std::string::npos) << e;
  // An element on its own line is reported at that line.
  auto rows = gtrack::ConfigTable::parse("r = [\n  [1, 2],\n  [3, \"x\"],\n]\n", "f.toml");
  e = error_of([&] { rows.number_rows("r", 2); });
  EXPECT_NE(e.find("f.toml:3: key 'r[1][1]': expected a number"), std::string::npos) << e;
  e = error_of([&] { t.number("missing"); });
  EXPECT_NE(e.find("missing"), std::string::npos) << e;
}

TEST(Config, IntegersAreNumbersButNotViceVersa) {
  auto t = gtrack::ConfigTable::parse("a = 3\nb = 2.5\n");
  EXPECT_DOUBLE_EQ(t.number("a"), 3.0);
  EXPECT_THROW(t.integer("b"), gtrack::ConfigError);
}

TEST(Config, SyntaxErrorHasFileAndLine) {
  std::string e = error_of([] { gtrack::ConfigTable::parse("a = 1\nb = = 2\n", "bad.toml"); });
  EXPECT_EQ(e.rfind("bad.toml:2:", 0), 0u) << e;
}

// A string left open says so, whichever quote it opened with and whether
// the file ends there or the next line follows.
TEST(Config, AnUnterminatedStringIsSaidToBeOne) {
  for (const char* text : {"a = 1\nname = 'open\nb = 2\n", "a = 1\nname = \"open\nb = 2\n", "a = 1\nname = \"open"}) {
    const std::string e = error_of([&] { gtrack::ConfigTable::parse(text, "s.toml"); });
    EXPECT_EQ(e, "s.toml:2: unterminated string (expected its closing quote before the end of the line)") << text;
  }
  // Other string errors keep the parser's own words.
  const std::string e = error_of([] { gtrack::ConfigTable::parse("name = \"a\x01b\"\n", "s.toml"); });
  EXPECT_NE(e.find("control characters"), std::string::npos) << e;
}

// A huge key or value is quoted short; a plugin name must be one.
TEST(Config, HugeTextIsQuotedShort) {
  auto t = gtrack::ConfigTable::parse(std::string(100000, 'k') + " = 1\n", "h.toml");
  std::string e = error_of([&] { t.check_all_used(); });
  EXPECT_NE(e.find("h.toml:1: key '" + std::string(60, 'k') + "... (100000 characters)': unknown key"),
            std::string::npos)
      << e.substr(0, 300);
  EXPECT_LT(e.size(), 300u);
  auto p = gtrack::ConfigTable::parse("[sensor]\nplugin = \"" + std::string(100000, 'A') + "\"\n", "h.toml");
  e = error_of([&] { gtrack::testing::loader().make_sensor(p.table("sensor")); });
  EXPECT_EQ(e, "h.toml:2: key 'sensor.plugin': expected a plugin name (letters, digits, '_' and '-', 1 to 64 "
               "characters), got '" + std::string(60, 'A') + "... (100000 characters)'");
  // A plugin's file given for its name.
  p = gtrack::ConfigTable::parse("[sensor]\nplugin = \"build/libgtrack_lab.so\"\n", "h.toml");
  e = error_of([&] { gtrack::testing::loader().make_sensor(p.table("sensor")); });
  EXPECT_NE(e.find("got 'build/libgtrack_lab.so'; a plugin is named without its folder or file name ('light' for "
                   "libgtrack_light.so)"),
            std::string::npos)
      << e;
}

TEST(Config, UnknownTableAtTopLevel) {
  auto t = gtrack::ConfigTable::parse("[sensr]\nx = 1\n[sensor]\ny = 2\n", "t.toml");
  t.table("sensor");
  std::string e = error_of([&] { t.check_all_used(); });
  EXPECT_NE(e.find("t.toml:1: key 'sensr'"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'sensor'"), std::string::npos) << e;
}

TEST(Config, ChoiceListsAllowedValues) {
  auto t = gtrack::ConfigTable::parse("mode = \"revesible\"\n");
  std::string e = error_of([&] { t.choice_or("mode", "x", {"reversible", "latching"}); });
  EXPECT_NE(e.find("did you mean \"reversible\""), std::string::npos) << e;
}

TEST(Config, MissingFileIsOneLine) {
  std::string e = error_of([] { gtrack::ConfigTable::load_file("/nonexistent/x.toml"); });
  EXPECT_NE(e.find("/nonexistent/x.toml"), std::string::npos);
}

using ConfigTableParse = gtrack::ConfigTable (*)(std::string_view, std::string);
using ConfigTableLoad = gtrack::ConfigTable (*)(const std::string&);

// file_path() takes a relative path from the config's folder, or from the
// folder given to parse(), and lists each key it resolved once, by its
// table, for every table of the document.
TEST(Config, FilePathsAreResolvedAndListed) {
  const std::string text = "top = \"a.txt\"\n[sensor]\ncalibration = \"cam/c.yml\"\nabs = \"/data/x.yml\"\n";
  const auto c = gtrack::ConfigTable::parse(text, "/lab/lab.toml");
  EXPECT_EQ(c.base_folder(), std::filesystem::path("/lab"));
  EXPECT_TRUE(c.named_files().empty());
  const auto sensor = c.table("sensor");
  EXPECT_EQ(sensor.file_path("calibration"), std::filesystem::path("/lab/cam/c.yml"));
  EXPECT_EQ(sensor.file_path("abs"), std::filesystem::path("/data/x.yml"));
  EXPECT_EQ(c.file_path("top"), std::filesystem::path("/lab/a.txt"));
  EXPECT_EQ(sensor.file_path("calibration"), std::filesystem::path("/lab/cam/c.yml"));
  const auto files = c.named_files();
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].name(), "[sensor] calibration");
  EXPECT_EQ(files[1].name(), "[sensor] abs");
  EXPECT_EQ(files[2].name(), "top");
  EXPECT_EQ(files[2].path, std::filesystem::path("/lab/a.txt"));
  const auto moved = gtrack::ConfigTable::parse(text, "/out/run_config.toml", "/lab");
  EXPECT_EQ(moved.table("sensor").file_path("calibration"), std::filesystem::path("/lab/cam/c.yml"));
  EXPECT_EQ(gtrack::ConfigTable::parse(text).file_path("top"), std::filesystem::path("a.txt"));
  // The signatures plugins built against earlier headers call are still
  // there (a default argument added to them would change their symbols).
  ConfigTableParse parse = &gtrack::ConfigTable::parse;
  ConfigTableLoad load = &gtrack::ConfigTable::load_file;
  EXPECT_EQ(parse(text, "/lab/lab.toml").base_folder(), std::filesystem::path("/lab"));
  EXPECT_THROW(load("/nonexistent/lab.toml"), gtrack::ConfigError);
}

// The first key whose value differs, in file order; comments, the order of
// keys and 32 against 32.0 do not count.
TEST(Config, FirstDifferenceNamesTheKeyAndBothValues) {
  const std::string base =
      "plugin_path = [\"a\"]\n[pso]\nparticles = 32\nw = 0.4\n[gripper]\nplugin = \"g\"\n"
      "[[gripper.links]]\nlength = 1.0\n[[gripper.links]]\nlength = 2.0\n";
  const auto a = gtrack::ConfigTable::parse(base, "a.toml");
  const auto same = gtrack::ConfigTable::parse(
      "# a note\nplugin_path = [\"a\"]\n[gripper]\nplugin = \"g\"\n[[gripper.links]]\nlength = 1\n[[gripper.links]]\nlength = 2\n"
      "[pso]\nw = 0.4   # inertia\nparticles = 32.0\n",
      "b.toml");
  EXPECT_FALSE(gtrack::first_difference(a, same).has_value());
  EXPECT_FALSE(gtrack::first_difference(a, a).has_value());

  const auto diff = [&](const std::string& text) {
    const auto d = gtrack::first_difference(a, gtrack::ConfigTable::parse(text, "c.toml"));
    return d ? d->key + ": " + d->first + " / " + d->second : std::string("none");
  };
  std::string changed = base;
  changed.replace(changed.find("32"), 2, "64");
  EXPECT_EQ(diff(changed), "[pso] particles: 32 / 64");
  EXPECT_EQ(diff(base + "[tracker]\nmirror_check = false\n"), "tracker: not set / a table");
  std::string nested = base;
  nested.replace(nested.find("2.0"), 3, "2.5");
  EXPECT_EQ(diff(nested), "[gripper] links: [{ length = 1 }, { length = 2 }] / [{ length = 1 }, { length = 2.5 }]");
  std::string missing = base;
  missing.erase(missing.find("w = 0.4\n"), 8);
  EXPECT_EQ(diff(missing), "[pso] w: 0.4 / not set");
  std::string text = base;
  text.replace(text.find("\"g\""), 3, "\"h\"");
  EXPECT_EQ(diff(text), "[gripper] plugin: 'g' / 'h'");
  EXPECT_EQ(diff("plugin_path = \"a\"\n[pso]\nparticles = 32\nw = 0.4\n"), "plugin_path: ['a'] / 'a'");
  // Long values differ where they differ, beyond what a message shows.
  const std::string long_name(200, 'x');
  const auto long_a = gtrack::ConfigTable::parse("note = \"" + long_name + "a\"\n");
  const auto long_b = gtrack::ConfigTable::parse("note = \"" + long_name + "b\"\n");
  EXPECT_TRUE(gtrack::first_difference(long_a, long_b).has_value());
  // Integers beyond 2^53 compare exactly; nan is the same as nan.
  EXPECT_TRUE(gtrack::first_difference(gtrack::ConfigTable::parse("n = 9007199254740993\n"),
                                       gtrack::ConfigTable::parse("n = 9007199254740992\n"))
                  .has_value());
  EXPECT_FALSE(gtrack::first_difference(gtrack::ConfigTable::parse("x = nan\n"), gtrack::ConfigTable::parse("x = nan\n"))
                   .has_value());
  // A table's own serialisation reads back as the same config.
  EXPECT_FALSE(gtrack::first_difference(a.table("pso"),
                                        gtrack::ConfigTable::parse(a.table("pso").toml_text())).has_value());
}

}  // namespace
