// data_defined: a gripper described entirely in TOML, no compiler needed.
//
// The model is read from the [gripper] table itself or, with model_file, from
// a separate TOML file (a relative path is taken from the config's folder).
// The format is documented in docs/plugins.md ("A gripper in a file"):
//   name; palm_mm = [[x, y], ...] (convex, counter-clockwise) with
//   [[finger]] tables (base_mm = [x, y], direction_deg, link_lengths_mm,
//   link_widths_mm: one more than links, the width at each hinge and at the
//   tip), or a [radial] table that generates palm and identical fingers
//   (fingers, palm_sides, palm_circumradius_mm, phase_deg, link_lengths_mm,
//   link_widths_mm); joint_min_deg, joint_max_deg; adjacent = [[1, 2], ...]
//   (1-based; default: each finger with the next, around);
//   max_adjacent_difference_deg, max_adjacent_sum_deg; symmetry_order;
//   unfolded_deg, folded_deg.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <gtrack/error.hpp>
#include <gtrack/gripper_config.hpp>
#include <cstdio>
#include <gtrack/log.hpp>
#include <gtrack/plugin.hpp>

namespace {

using gtrack::ConfigTable;
using gtrack::Range;

constexpr double kMaxMm = gtrack::ArticulatedModel::kMaxSizeMm;
const Range kLength = Range::closed(gtrack::ArticulatedModel::kMinSizeMm, kMaxMm);  // [0.001, 100] mm
const Range kPlace = Range::closed(-kMaxMm, kMaxMm);

std::vector<gtrack::LinkShape> read_links(const ConfigTable& t) {
  const auto lengths = t.numbers("link_lengths_mm", std::nullopt, kLength);
  if (lengths.empty()) t.fail("link_lengths_mm", "needs at least one link");
  const auto widths = t.numbers("link_widths_mm", lengths.size() + 1, Range::closed(0, kMaxMm));
  return gtrack::links_from_config(t, lengths, widths);
}

// The finger leaves the palm: its direction within 90 deg of the outward
// normal of an edge its base is on (either edge, at a corner). A finger
// drawn inwards or along the edge crosses the palm, or lies on its outline.
void check_outward(const ConfigTable& f, const gtrack::FingerShape& finger, const std::vector<Eigen::Vector2d>& palm,
                   double tolerance) {
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  const Eigen::Vector2d d(std::cos(finger.direction_deg * kDeg), std::sin(finger.direction_deg * kDeg));
  double best = -2, normal_deg = 0;
  for (size_t i = 0; i < palm.size(); ++i) {
    const Eigen::Vector2d a = palm[i], b = palm[(i + 1) % palm.size()];
    if (gtrack::distance_to_outline(finger.base_mm, {a, b}) > tolerance) continue;
    const Eigen::Vector2d n = Eigen::Vector2d(b.y() - a.y(), a.x() - b.x()).normalized();  // counter-clockwise: outward
    if (n.dot(d) > best) best = n.dot(d), normal_deg = std::atan2(n.y(), n.x()) / kDeg;
  }
  if (best > -2 && best <= 1e-6) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "%g points into the palm or along its edge from the base [%g, %g] (the edge's outward normal is "
                  "at %.4g deg); expected a direction out of the palm, less than 90 deg from that normal",
                  finger.direction_deg, finger.base_mm.x(), finger.base_mm.y(), normal_deg);
    f.fail("direction_deg", text);
  }
}

gtrack::GripperGeometry read_geometry(const ConfigTable& t) {
  if (t.path().empty() && t.has("gripper")) {
    // A model file written as a config's [gripper] table.
    t.fail("gripper", "a model file holds the gripper's keys at its top level (name, palm_mm, [[finger]]), not "
                      "in a [gripper] table");
  }
  gtrack::GripperGeometry g;
  const std::string name = t.string_or("name", "data_defined");
  if (t.has("radial")) {
    if (t.has("finger") || t.has("palm_mm")) t.fail("radial", "give either [radial] or palm_mm with [[finger]]");
    const ConfigTable r = t.table("radial");
    gtrack::RadialGripperSpec spec;
    spec.name = name;
    spec.fingers = static_cast<int>(r.integer("fingers", Range{1, 64}));
    // By default one side per finger; two fingers get a square palm (the
    // smallest polygon whose sides are a multiple of the fingers).
    const int sides = spec.fingers * ((3 + spec.fingers - 1) / spec.fingers);
    spec.palm_sides = static_cast<int>(r.integer_or("palm_sides", sides, Range{3, 256}));
    if (spec.palm_sides % spec.fingers != 0) r.fail("palm_sides", "must be a multiple of fingers");
    spec.palm_circumradius_mm = r.number("palm_circumradius_mm", kLength);
    spec.finger_phase_deg = r.number_or("phase_deg", 0.0, Range::closed(-360, 360));
    spec.links = read_links(r);
    r.check_all_used();
    g = gtrack::make_radial_gripper(spec);
  } else {
    for (const auto& p : t.number_rows("palm_mm", 2, kPlace)) g.palm_mm.emplace_back(p[0], p[1]);
    if (g.palm_mm.size() < 3) t.fail("palm_mm", "the palm needs at least 3 points");
    if (const std::string bent = gtrack::palm_shape_mismatch(g.palm_mm); !bent.empty()) t.fail("palm_mm", bent);
    const auto fingers = t.tables("finger");
    if (fingers.empty()) {
      const std::string array = "[[" + (t.path().empty() ? std::string() : t.path() + ".") + "finger]]";
      t.fail("finger", "missing; add one " + array + " table per finger, after the " +
                           (t.path().empty() ? std::string("top-level") : "[" + t.path() + "]") +
                           " keys (or use [radial])");
    }
    double palm_radius = 0;
    for (const auto& p : g.palm_mm) palm_radius = std::max(palm_radius, p.norm());
    for (const auto& f : fingers) {
      gtrack::FingerShape F;
      auto b = f.numbers("base_mm", 2, kPlace);
      F.base_mm = {b[0], b[1]};
      // The first hinge sits on the palm's outline; a finger elsewhere is
      // drawn floating, or out of the palm's middle, without a word.
      const double off = gtrack::distance_to_outline(F.base_mm, g.palm_mm);
      if (off > 0.05 * palm_radius) {
        char text[160];
        std::snprintf(text, sizeof text, "[%g, %g] is %.3g mm off the palm's outline; expected a point on it",
                      b[0], b[1], off);
        f.fail("base_mm", text);
      }
      F.direction_deg = f.number("direction_deg", Range::closed(-360, 360));
      check_outward(f, F, g.palm_mm, 0.05 * palm_radius);
      F.links = read_links(f);
      f.check_all_used();
      g.fingers.push_back(F);
    }
    g.collision.adjacent = gtrack::ring_adjacency(static_cast<int>(g.fingers.size()));
  }
  g.name = name;
  if (t.has("adjacent")) {
    g.collision.adjacent.clear();
    for (const auto& p : t.number_rows("adjacent", 2, Range::closed(1, static_cast<double>(g.fingers.size())))) {
      if (p[0] != std::floor(p[0]) || p[1] != std::floor(p[1])) {
        t.fail("adjacent", "expected pairs of whole finger numbers (1-based)");
      }
      if (p[0] == p[1]) t.fail("adjacent", "a finger cannot be adjacent to itself");
      const std::pair<int, int> pair(static_cast<int>(p[0]) - 1, static_cast<int>(p[1]) - 1);
      for (const auto& [a, b] : g.collision.adjacent) {
        if ((a == pair.first && b == pair.second) || (a == pair.second && b == pair.first)) {
          t.fail("adjacent", "fingers " + std::to_string(a + 1) + " and " + std::to_string(b + 1) +
                                 " are paired twice; expected each pair once (it would count twice in K(H))");
        }
      }
      g.collision.adjacent.push_back(pair);
    }
  }
  g.joint_min_deg = t.number_or("joint_min_deg", 0, Range::closed(-180, 180));
  g.joint_max_deg = t.number_or("joint_max_deg", 90, Range::closed(-180, 180));
  if (!(g.joint_min_deg < g.joint_max_deg)) {
    char text[128];
    std::snprintf(text, sizeof text, "%g must be greater than joint_min_deg (%g)", g.joint_max_deg, g.joint_min_deg);
    t.fail("joint_max_deg", text);
  }
  g.collision.max_difference_deg = t.number_or("max_adjacent_difference_deg", 45, Range::positive());
  g.collision.max_sum_deg = t.number_or("max_adjacent_sum_deg", 1e9, Range::positive());
  // Default: what the geometry has already; a radial gripper is symmetric
  // under a turn by one finger, one drawn finger by finger is not.
  // Both are joint values the tracker starts from: within the limits.
  const Range limits = Range::closed(g.joint_min_deg, g.joint_max_deg);
  g.unfolded_deg = t.number_or("unfolded_deg", std::clamp(0.0, g.joint_min_deg, g.joint_max_deg), limits);
  g.folded_deg = t.number_or("folded_deg", std::clamp(60.0, g.joint_min_deg, g.joint_max_deg), limits);
  g.symmetry_order = static_cast<int>(t.integer_or("symmetry_order", g.symmetry_order, Range{1, 64}));
  if (const std::string broken = gtrack::symmetry_mismatch(g); !broken.empty()) {
    // A misspelt [[finger]] leaves a finger out, which breaks the symmetry:
    // the unknown key is the cause to name.
    t.check_all_used();
    t.fail("symmetry_order", broken);
  }
  // A gripper drawn finger by finger whose palm and fingers a turn maps onto
  // themselves, with no symmetry_order: its poses a turn apart would be told
  // apart as if it were marked, and a sequence of it scored a turn off.
  const int F = static_cast<int>(g.fingers.size());
  if (!t.has("symmetry_order") && !t.has("radial") && F > 1) {
    for (int k = F; k >= 2; --k) {
      gtrack::GripperGeometry turned = g;
      turned.symmetry_order = k;
      if (F % k != 0 || !gtrack::symmetry_mismatch(turned).empty()) continue;
      gtrack::logger().warn("{}: not set, but a turn by {:g} deg maps the palm and every finger onto themselves: "
                            "poses a turn apart are told apart as if the gripper were marked (and scored a turn "
                            "off); set symmetry_order = {}, or = 1 if a mark does tell them apart",
                            t.where("symmetry_order"), 360.0 / k, k);
      break;
    }
  }
  return g;
}

gtrack::ArticulatedModel load_model(const ConfigTable& t) {
  if (!t.has("model_file")) return gtrack::ArticulatedModel(read_geometry(t));
  const std::filesystem::path file = t.file_path("model_file");
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) t.fail("model_file", file.string() + " is a folder; expected a TOML file");
  if (!std::filesystem::exists(file, ec)) t.fail("model_file", file.string() + " does not exist");
  if (!std::filesystem::is_regular_file(file, ec)) {
    t.fail("model_file", file.string() + " is not a regular file; expected a TOML file");
  }
  const ConfigTable m = ConfigTable::load_file(file.string());
  gtrack::GripperGeometry g = read_geometry(m);
  m.check_all_used();
  return gtrack::ArticulatedModel(std::move(g));
}

class DataDefinedGripper final : public gtrack::Gripper {
 public:
  explicit DataDefinedGripper(const ConfigTable& t) try : model_(load_model(t)) {
  } catch (const gtrack::ConfigError&) {
    throw;
  } catch (const gtrack::Error& e) {
    // Geometry checks of the framework: say which table they are about.
    throw gtrack::ConfigError(t.where("plugin") + ": " + e.what());
  }
  const gtrack::ArticulatedModel& model() const override { return model_; }

 private:
  gtrack::ArticulatedModel model_;
};

}  // namespace

GTRACK_PLUGIN(DataDefinedGripper, gtrack::Gripper, "data_defined", "1.0.0",
              "any gripper described in TOML: palm polygon, fingers as planar link chains")
