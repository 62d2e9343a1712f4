// The gripper defined only in TOML: both forms, a separate model file, errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <gtrack/gripper_config.hpp>

#include "support/logged.hpp"
#include "support/plugins.hpp"

using gtrack::testing::make_gripper;

namespace {

const std::string kFourFinger = R"(plugin = "data_defined"
name = "four_finger"
palm_mm = [[0.4, 0.0], [0.0, 0.4], [-0.4, 0.0], [0.0, -0.4]]
symmetry_order = 4
[[finger]]
base_mm = [0.2, 0.2]
direction_deg = 45
link_lengths_mm = [0.3, 0.3]
link_widths_mm = [0.4, 0.3, 0.0]
[[finger]]
base_mm = [-0.2, 0.2]
direction_deg = 135
link_lengths_mm = [0.3, 0.3]
link_widths_mm = [0.4, 0.3, 0.0]
[[finger]]
base_mm = [-0.2, -0.2]
direction_deg = 225
link_lengths_mm = [0.3, 0.3]
link_widths_mm = [0.4, 0.3, 0.0]
[[finger]]
base_mm = [0.2, -0.2]
direction_deg = 315
link_lengths_mm = [0.3, 0.3]
link_widths_mm = [0.4, 0.3, 0.0]
)";

TEST(DataDefinedGripper, ExplicitFingers) {
  auto g = make_gripper(kFourFinger);
  const auto& m = g->model();
  EXPECT_EQ(m.fingers(), 4);
  EXPECT_EQ(m.dims(), 10);
  EXPECT_EQ(m.triangles(), 2 + 4 * 3);
  EXPECT_EQ(m.geometry().collision.adjacent.size(), 4u);
  Eigen::VectorXd h = Eigen::VectorXd::Zero(10);
  auto tips = m.fingertips(h);
  const double r = std::hypot(0.2, 0.2) + 0.6;
  EXPECT_NEAR(tips[0].x(), r * std::cos(M_PI / 4), 1e-9);
  EXPECT_NEAR(tips[0].y(), r * std::sin(M_PI / 4), 1e-9);
  // The symmetry is usable: a quarter turn maps fingertips onto fingertips.
  h << 0, 0, 50, 10, 20, 30, 5, 15, 25, 35;
  auto e = m.symmetric_equivalent(h, 1);
  auto a = m.fingertips(h), b = m.fingertips(e);
  for (const auto& p : a) {
    double best = 1e9;
    for (const auto& q : b) best = std::min(best, (p - q).norm());
    EXPECT_LT(best, 1e-9);
  }
}

TEST(DataDefinedGripper, RadialFormAndModelFile) {
  auto g = make_gripper(
      "plugin = \"data_defined\"\n[radial]\nfingers = 5\npalm_circumradius_mm = 0.5\n"
      "link_lengths_mm = [0.2, 0.2, 0.2]\nlink_widths_mm = [0.3, 0.25, 0.2, 0]\n");
  EXPECT_EQ(g->model().fingers(), 5);
  EXPECT_EQ(g->model().triangles(), 3 + 5 * 5);
  // A radial gripper looks the same after a turn by one finger.
  EXPECT_EQ(g->model().geometry().symmetry_order, 5);
  // Two fingers need a palm with a multiple of two sides: a square by default.
  auto two = make_gripper(
      "plugin = \"data_defined\"\n[radial]\nfingers = 2\npalm_circumradius_mm = 0.3\n"
      "link_lengths_mm = [0.2]\nlink_widths_mm = [0.2, 0.1]\n");
  EXPECT_EQ(two->model().fingers(), 2);
  EXPECT_EQ(two->model().geometry().palm_mm.size(), 4u);
  EXPECT_EQ(two->model().geometry().symmetry_order, 2);

  const auto dir = std::filesystem::temp_directory_path() / "gtrack_data_defined_test";
  std::filesystem::create_directories(dir);
  std::string body = kFourFinger.substr(kFourFinger.find('\n') + 1);  // without the plugin line
  std::ofstream(dir / "four.toml") << body;
  std::ofstream(dir / "config.toml") << "[gripper]\nplugin = \"data_defined\"\nmodel_file = \"four.toml\"\n";
  auto root = gtrack::ConfigTable::load_file((dir / "config.toml").string());
  auto g2 = gtrack::testing::loader().make_gripper(root.table("gripper"));
  EXPECT_EQ(g2->model().fingers(), 4);
}

// One [[finger]] table: a single link 0.3 mm long, hinged at (x, y).
std::string finger_table(double x, double y, double direction_deg) {
  char text[200];
  std::snprintf(text, sizeof text,
                "[[finger]]\nbase_mm = [%.2f, %.2f]\ndirection_deg = %g\nlink_lengths_mm = [0.3]\n"
                "link_widths_mm = [0.2, 0.1]\n",
                x, y, direction_deg);
  return text;
}

// `text` with its first `from` replaced by `to`.
std::string with(std::string text, const std::string& from, const std::string& to) {
  return text.replace(text.find(from), from.size(), to);
}

std::string config_error(const std::string& toml) {
  try {
    make_gripper(toml);
  } catch (const gtrack::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(DataDefinedGripper, MistakesAreLocated) {
  // Clockwise palm.
  std::string clockwise = kFourFinger;
  clockwise.replace(clockwise.find("[[0.4, 0.0], [0.0, 0.4], [-0.4, 0.0], [0.0, -0.4]]"), 50,
                    "[[0.4, 0.0], [0.0, -0.4], [-0.4, 0.0], [0.0, 0.4]]");
  EXPECT_NE(config_error(clockwise).find("<test>:3: key 'palm_mm'"), std::string::npos) << config_error(clockwise);
  // A concave palm (the fan of triangles would cover its notch), a bowtie
  // whose lobes leave a positive area, and a pentagram, which turns left at
  // every point but winds around twice.
  for (const auto& [palm, said] : std::vector<std::pair<std::string, std::string>>{
           {"[[0.4, 0.0], [0.0, 0.4], [0.0, 0.1], [-0.4, 0.0], [0.0, -0.4]]", "is not convex: point 3 lies 0.2"},
           {"[[0.0, 0.1], [0.3, 0.0], [0.3, 0.2], [0.0, 0.0]]", "crosses itself"},
           {"[[0.4, 0.0], [-0.3236, 0.2351], [0.1236, -0.3804], [0.1236, 0.3804], [-0.3236, -0.2351]]",
            "crosses itself"},
           // A crescent: each point barely inside its neighbours' line, the
           // inner arc far inside the hull.
           {"[[0.45, -0.2], [0.39, 0.025], [0.225, 0.19], [0.0, 0.25], [-0.225, 0.19], [-0.39, 0.025], "
            "[-0.45, -0.2], [-0.35, -0.2], [-0.303, -0.025], [-0.175, 0.103], [0.0, 0.15], [0.175, 0.103], "
            "[0.303, -0.025], [0.35, -0.2]]",
            "is not convex: point 9 lies"}}) {
    std::string bent = kFourFinger;
    bent.replace(bent.find("[[0.4, 0.0], [0.0, 0.4], [-0.4, 0.0], [0.0, -0.4]]"), 50, palm);
    bent.replace(bent.find("symmetry_order = 4"), 18, "symmetry_order = 1");
    const std::string e = config_error(bent);
    EXPECT_NE(e.find("<test>:3: key 'palm_mm': the palm polygon " + said), std::string::npos) << palm << ": " << e;
  }
  // Widths do not match the links.
  std::string widths = kFourFinger;
  widths.replace(widths.find("link_widths_mm = [0.4, 0.3, 0.0]"), 32, "link_widths_mm = [0.4, 0.3]");
  EXPECT_NE(config_error(widths).find("finger[0].link_widths_mm"), std::string::npos) << config_error(widths);
  // A misspelled key inside a finger.
  std::string typo = kFourFinger;
  typo.replace(typo.find("direction_deg = 45"), 18, "directon_deg = 45");
  const std::string e = config_error(typo);
  EXPECT_NE(e.find("is 'directon_deg' on line 7 a misspelling of it?"), std::string::npos) << e;
  // No fingers at all.
  EXPECT_NE(config_error("plugin = \"data_defined\"\npalm_mm = [[1,0],[0,1],[-1,0]]\n").find("finger"),
            std::string::npos);
  // Adjacency naming a finger that does not exist.
  EXPECT_NE(config_error(kFourFinger + "adjacent = [[1, 5]]\n").find("adjacent"), std::string::npos);
  // A pair that is no pair of whole fingers, or a finger paired with itself
  // (top-level keys, so before the first [[finger]]).
  const auto with_adjacent = [](const std::string& pairs) {
    std::string t = kFourFinger;
    return t.insert(t.find("[[finger]]"), "adjacent = " + pairs + "\n");
  };
  EXPECT_EQ(config_error(with_adjacent("[[1, 2], [2, 3], [3, 4], [4, 1]]")), "");
  std::string half = config_error(with_adjacent("[[1.5, 2]]"));
  EXPECT_NE(half.find("key 'adjacent': expected pairs of whole finger numbers"), std::string::npos) << half;
  std::string twice = config_error(with_adjacent("[[1, 2], [2, 3], [2, 1]]"));
  EXPECT_NE(twice.find("key 'adjacent': fingers 1 and 2 are paired twice"), std::string::npos) << twice;
  std::string self = config_error(with_adjacent("[[2, 2]]"));
  EXPECT_NE(self.find("key 'adjacent': a finger cannot be adjacent to itself"), std::string::npos) << self;
  // Sizes no micro-gripper has: refused with the key and the bound.
  std::string huge = kFourFinger;
  huge.replace(huge.find("link_lengths_mm = [0.3, 0.3]"), 28, "link_lengths_mm = [0.3, 1e300]");
  const std::string h = config_error(huge);
  EXPECT_NE(h.find("finger[0].link_lengths_mm[1]': value 1e+300 is out of range; expected a number in [0.001, 100]"),
            std::string::npos)
      << h;
  // Sizes with no area at any render size: refused, not a gripper of its
  // palm alone, or a palm with no area blamed on another key.
  std::string tiny = kFourFinger;
  tiny.replace(tiny.find("link_lengths_mm = [0.3, 0.3]"), 28, "link_lengths_mm = [0.3, 1e-300]");
  EXPECT_NE(config_error(tiny).find("finger[0].link_lengths_mm[1]': value 1e-300 is out of range"), std::string::npos)
      << config_error(tiny);
  const std::string radial = "plugin = \"data_defined\"\n[radial]\nfingers = 4\npalm_circumradius_mm = 0.5\n"
                             "link_lengths_mm = [0.4]\nlink_widths_mm = [0.4, 0]\n";
  const std::string speck = with(radial, "palm_circumradius_mm = 0.5", "palm_circumradius_mm = 1e-300");
  EXPECT_NE(config_error(speck).find("key 'radial.palm_circumradius_mm': value 1e-300 is out of range"), std::string::npos)
      << config_error(speck);
  const std::string spun = radial + "phase_deg = 1e17\n";
  EXPECT_NE(config_error(spun).find("key 'radial.phase_deg'"), std::string::npos) << config_error(spun);
  std::string far = kFourFinger;
  far.replace(far.find("base_mm = [0.2, 0.2]"), 20, "base_mm = [0.2, 500]");
  EXPECT_NE(config_error(far).find("finger[0].base_mm"), std::string::npos) << config_error(far);
  // A hinge off the palm's outline (a finger floating beside it, or one from
  // the palm's middle) is refused, naming the finger.
  const std::string floating = with(kFourFinger, "base_mm = [-0.2, 0.2]", "base_mm = [-0.5, 0.4]");
  EXPECT_NE(config_error(floating).find("key 'finger[1].base_mm': [-0.5, 0.4] is 0.354 mm off the palm's outline; "
                                        "expected a point on it"),
            std::string::npos)
      << config_error(floating);
  EXPECT_NE(config_error(with(kFourFinger, "base_mm = [0.2, 0.2]", "base_mm = [0, 0]")).find("finger[0].base_mm"),
            std::string::npos);
  // A finger drawn into the palm, or along the edge its hinge is on, is
  // refused with the edge's outward direction; one slanted outwards passes.
  const std::string inward = with(kFourFinger, "direction_deg = 45", "direction_deg = 225");
  EXPECT_NE(config_error(inward).find("key 'finger[0].direction_deg': 225 points into the palm or along its edge "
                                      "from the base [0.2, 0.2] (the edge's outward normal is at 45 deg)"),
            std::string::npos)
      << config_error(inward);
  EXPECT_NE(config_error(with(kFourFinger, "direction_deg = 45", "direction_deg = 135")).find("along its edge"),
            std::string::npos);
  const std::string slanted = with(with(kFourFinger, "direction_deg = 45", "direction_deg = 100"),
                                   "symmetry_order = 4", "symmetry_order = 1");
  EXPECT_EQ(config_error(slanted), "");
  // Joint limits the wrong way round are shown.
  EXPECT_NE(config_error(with(kFourFinger, "symmetry_order = 4\n", "symmetry_order = 4\njoint_min_deg = 30\njoint_max_deg = 10\n"))
                .find("key 'joint_max_deg': 10 must be greater than joint_min_deg (30)"),
            std::string::npos);
  // A misspelt [[finger]] leaves a finger out, which breaks the symmetry:
  // the misspelling is what is named.
  std::string misspelt = kFourFinger;
  misspelt.replace(misspelt.rfind("[[finger]]"), 10, "[[fingers]]");
  EXPECT_NE(config_error(misspelt).find("key 'fingers': unknown key"), std::string::npos) << config_error(misspelt);
  // Links each within the bound that together reach past it from the palm.
  std::string reach = kFourFinger;
  for (size_t at; (at = reach.find("link_lengths_mm = [0.3, 0.3]")) != std::string::npos;) {
    reach.replace(at, 28, "link_lengths_mm = [60, 60]");
  }
  EXPECT_NE(config_error(reach).find("a part is 120.283 mm long or away from the palm centre"), std::string::npos)
      << config_error(reach);
}

// A gripper drawn finger by finger that a turn maps onto itself, with no
// symmetry_order, is warned about with the order to set; one that says
// its order, or says 1 (a mark tells the turns apart), is not.
TEST(DataDefinedGripper, AnUnsaidSymmetryIsPointedOut) {
  const std::string unsaid = with(kFourFinger, "symmetry_order = 4\n", "");
  const std::string said = gtrack::testing::logged([&] { make_gripper(unsaid); });
  EXPECT_NE(said.find("key 'symmetry_order': not set, but a turn by 90 deg maps the palm and every finger onto "
                      "themselves"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("set symmetry_order = 4"), std::string::npos) << said;
  EXPECT_EQ(make_gripper(unsaid)->model().geometry().symmetry_order, 1);
  for (const std::string& order : {"symmetry_order = 4\n", "symmetry_order = 1\n"}) {
    const std::string quiet = gtrack::testing::logged([&] { make_gripper(with(kFourFinger, "symmetry_order = 4\n", order)); });
    EXPECT_EQ(quiet.find("symmetry_order"), std::string::npos) << order << quiet;
  }
  // A half turn only (one finger longer on each side): order 2 is said.
  std::string two = with(unsaid, "link_lengths_mm = [0.3, 0.3]", "link_lengths_mm = [0.3, 0.4]");
  two = with(two.substr(0, two.find("[[finger]]\nbase_mm = [-0.2, -0.2]")) +
                 two.substr(two.find("[[finger]]\nbase_mm = [-0.2, -0.2]")),
             "base_mm = [-0.2, -0.2]\ndirection_deg = 225\nlink_lengths_mm = [0.3, 0.3]",
             "base_mm = [-0.2, -0.2]\ndirection_deg = 225\nlink_lengths_mm = [0.3, 0.4]");
  const std::string half = gtrack::testing::logged([&] { make_gripper(two); });
  EXPECT_NE(half.find("a turn by 180 deg maps"), std::string::npos) << half;
}

// symmetry_order is checked against the shape: a quarter turn does not map a
// two-finger gripper onto itself, nor a rectangle's palm; eval and the
// tracker's search would otherwise take a turned pose for the same one.
TEST(DataDefinedGripper, ASymmetryTheShapeDoesNotHaveIsRefused) {
  std::string two = kFourFinger;
  two = two.substr(0, two.find("[[finger]]\nbase_mm = [-0.2, 0.2]")) +
        two.substr(two.find("[[finger]]\nbase_mm = [-0.2, -0.2]"));
  two.erase(two.find("[[finger]]\nbase_mm = [0.2, -0.2]"));
  const std::string e = config_error(two);
  EXPECT_NE(e.find("<test>:4: key 'symmetry_order': a turn by 90 deg takes finger 1's hinge to [-0.2, 0.2], "
                   "where no finger has its hinge"),
            std::string::npos)
      << e;
  EXPECT_EQ(config_error(with(two, "symmetry_order = 4", "symmetry_order = 2")), "");
  std::string oblong = with(with(kFourFinger, "[[0.4, 0.0], [0.0, 0.4]", "[[0.6, 0.0], [0.0, 0.4]"),
                                  "base_mm = [0.2, 0.2]", "base_mm = [0.3, 0.2]");
  oblong = with(oblong, "base_mm = [0.2, -0.2]", "base_mm = [0.3, -0.2]");
  EXPECT_NE(config_error(oblong).find("takes palm point 1 [0.6, 0] to [0, 0.6], 0.2 mm off the palm's outline"),
            std::string::npos)
      << config_error(oblong);
  std::string longer = kFourFinger;
  longer.replace(longer.rfind("link_lengths_mm = [0.3, 0.3]"), 28, "link_lengths_mm = [0.3, 0.4]");
  EXPECT_NE(config_error(longer).find("key 'symmetry_order': a turn by 90 deg takes finger 3 onto finger 4, "
                                      "whose links differ"),
            std::string::npos)
      << config_error(longer);
  const std::string turned = with(kFourFinger, "direction_deg = 135", "direction_deg = 150");
  EXPECT_NE(config_error(turned).find("takes finger 1's direction to 135 deg, where finger 2 at its hinge points "
                                      "to 150 deg"),
            std::string::npos)
      << config_error(turned);
  // Hand-typed coordinates of a regular shape are the shape: a few um off,
  // or rounded to 0.01 mm on a palm 0.4 mm across.
  EXPECT_EQ(config_error(with(kFourFinger, "base_mm = [0.2, 0.2]", "base_mm = [0.201, 0.199]")), "");
  // A round palm of many points, whose turn by a third lands between them
  // (on its outline), with three fingers; its points rounded to 0.01 mm, so
  // that some repeat.
  std::string round = "plugin = \"data_defined\"\nsymmetry_order = 3\npalm_mm = [";
  for (int i = 0; i < 256; ++i) {
    char p[48];
    std::snprintf(p, sizeof p, "%s[%.2f, %.2f]", i ? ", " : "", 0.5 * std::cos(2 * M_PI * i / 256),
                  0.5 * std::sin(2 * M_PI * i / 256));
    round += p;
  }
  round += "]\n";
  for (int f = 0; f < 3; ++f) round += finger_table(0.5 * std::cos(2 * M_PI * f / 3), 0.5 * std::sin(2 * M_PI * f / 3), 120 * f);
  EXPECT_EQ(config_error(round), "");
  // Two fingers on one hinge, each side (a V): a half turn takes each onto
  // the one of the other side's pair that points its way.
  std::string vee = "plugin = \"data_defined\"\nsymmetry_order = 2\n"
                    "palm_mm = [[0.45, -0.3], [0.45, 0.3], [-0.45, 0.3], [-0.45, -0.3]]\n";
  for (const auto& [x, d] : std::vector<std::pair<double, int>>{{0.45, 30}, {0.45, -30}, {-0.45, 210}, {-0.45, 150}}) {
    vee += finger_table(x, 0, d);
  }
  EXPECT_EQ(config_error(vee), "");
}

// Two parallel fingers on each side (a fork): a half turn takes each finger
// to the one its hinge lands on, not to either finger of the opposite
// direction, so the turned pose has the same joints in other slots.
TEST(DataDefinedGripper, AHalfTurnOfAForkMapsFingersByTheirHinges) {
  auto g = make_gripper("plugin = \"data_defined\"\nsymmetry_order = 2\n"
                        "palm_mm = [[0.5, -0.4], [0.5, 0.4], [-0.5, 0.4], [-0.5, -0.4]]\n" +
                        finger_table(0.5, 0.2, 0) + finger_table(0.5, -0.2, 0) + finger_table(-0.5, -0.2, 180) +
                        finger_table(-0.5, 0.2, 180));
  const auto& m = g->model();
  Eigen::VectorXd h(10);
  h << 0, 0, 100, 10, 5, 0, 10, 20, 30, 40;
  const Eigen::VectorXd e = m.symmetric_equivalent(h, 1);
  EXPECT_EQ(e.tail(4), (Eigen::Vector4d(30, 40, 10, 20))) << e.transpose();
  const auto a = m.link_endpoints(h), b = m.link_endpoints(e);
  for (const auto& p : a) {
    double best = 1e9;
    for (const auto& q : b) best = std::min(best, (p - q).norm());
    EXPECT_LT(best, 1e-9);
  }
}

// A model_file that is missing or a folder is named with the key that
// names it.
TEST(DataDefinedGripper, AMissingModelFileNamesItsKey) {
  const std::string missing = config_error("plugin = \"data_defined\"\nmodel_file = \"/nonexistent/m.toml\"\n");
  EXPECT_NE(missing.find("key 'model_file': /nonexistent/m.toml does not exist"), std::string::npos) << missing;
  const std::string folder = config_error("plugin = \"data_defined\"\nmodel_file = \"/tmp\"\n");
  EXPECT_NE(folder.find("key 'model_file': /tmp is a folder"), std::string::npos) << folder;
  // A model file written as a config's [gripper] table is told where its
  // keys go.
  const auto file = std::filesystem::temp_directory_path() / "gtrack_model_in_a_table.toml";
  std::string tabled = "[gripper]\n" + with(kFourFinger, "[[finger]]", "[[gripper.finger]]");
  tabled = with(tabled, "plugin = \"data_defined\"\n", "");
  std::ofstream(file) << tabled;
  const std::string in_table =
      config_error("plugin = \"data_defined\"\nmodel_file = \"" + file.string() + "\"\n");
  EXPECT_NE(in_table.find("key 'gripper': a model file holds the gripper's keys at its top level"), std::string::npos)
      << in_table;
  std::filesystem::remove(file);
}

// More links than the renderers have slots for: refused when the model is
// made (so synth refuses it as track does), naming the count and the limit.
TEST(DataDefinedGripper, TooManyLinksIsRefusedAtLoad) {
  const std::string ok = "plugin = \"data_defined\"\n[radial]\nfingers = 64\npalm_circumradius_mm = 1\n"
                         "link_lengths_mm = [0.1, 0.1, 0.1]\nlink_widths_mm = [0.05, 0.05, 0.05, 0]\n";
  EXPECT_EQ(config_error(ok), "");  // 192 links
  std::string over = ok;
  over.replace(over.find("[0.1, 0.1, 0.1]"), 15, "[0.1, 0.1, 0.1, 0.1]");
  over.replace(over.find("[0.05, 0.05, 0.05, 0]"), 21, "[0.05, 0.05, 0.05, 0.05, 0]");
  const std::string e = config_error(over);
  EXPECT_NE(e.find("256 links over its 64 fingers; at most 255 are supported"), std::string::npos) << e;
}

}  // namespace

// A radial gripper plugin's own defaults with a width too few: the error
// is its author's (the defaults), not a key of the config, which sets none.
TEST(RadialGripper, DefaultsWithAWidthTooFewBlameTheDefaults) {
  gtrack::RadialGripperDefaults d;
  d.spec.name = "quad";
  d.spec.fingers = 4;
  d.spec.palm_sides = 4;
  d.spec.palm_circumradius_mm = 0.4;
  for (double length : {0.36, 0.36}) d.spec.links.push_back({length, 0, 0});
  d.widths_mm = {0.4, 0.3};
  const auto table = gtrack::ConfigTable::parse("plugin = \"quad\"\n", "quad.toml");
  try {
    gtrack::radial_gripper_from_config(table, d);
    FAIL() << "the defaults were taken";
  } catch (const gtrack::Error& e) {
    EXPECT_EQ(std::string(e.what()), "the gripper plugin's built-in defaults have 2 links and 2 widths; expected 3 "
                                     "(RadialGripperDefaults::widths_mm: the width at each hinge and at the tip)");
  }
  d.widths_mm = {0.4, 0.3, 0.2};
  EXPECT_EQ(gtrack::radial_gripper_from_config(table, d).fingers.size(), 4u);
}
