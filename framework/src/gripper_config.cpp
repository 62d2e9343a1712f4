// Radial gripper geometry from a [gripper] table with built-in defaults.
#include "gtrack/gripper_config.hpp"

#include <algorithm>

#include "gtrack/error.hpp"

namespace gtrack {

std::vector<LinkShape> links_from_config(const ConfigTable& t, const std::vector<double>& lengths,
                                         const std::vector<double>& widths) {
  if (widths.size() != lengths.size() + 1) {
    t.fail("link_widths_mm", "expected " + std::to_string(lengths.size() + 1) + " widths (one more than the " +
                                 std::to_string(lengths.size()) + " links), got " + std::to_string(widths.size()));
  }
  std::vector<LinkShape> links;
  for (size_t j = 0; j < lengths.size(); ++j) {
    if (widths[j] <= 0 && widths[j + 1] <= 0) {
      t.fail("link_widths_mm", "link " + std::to_string(j + 1) + " is 0 wide at both ends; a link needs a width at "
                                                                     "one end at least");
    }
    links.push_back({lengths[j], widths[j], widths[j + 1]});
  }
  return links;
}

GripperGeometry radial_gripper_from_config(const ConfigTable& t, RadialGripperDefaults d) {
  // The plugin's own defaults first: a mistake there is its author's, not
  // the config's.
  if (d.widths_mm.size() != d.spec.links.size() + 1) {
    throw Error("the gripper plugin's built-in defaults have " + std::to_string(d.spec.links.size()) + " link" +
                (d.spec.links.size() == 1 ? "" : "s") + " and " + std::to_string(d.widths_mm.size()) +
                " widths; expected " + std::to_string(d.spec.links.size() + 1) +
                " (RadialGripperDefaults::widths_mm: the width at each hinge and at the tip)");
  }
  RadialGripperSpec spec = d.spec;
  const Range size = Range::closed(ArticulatedModel::kMinSizeMm, ArticulatedModel::kMaxSizeMm);
  spec.palm_circumradius_mm = t.number_or("palm_circumradius_mm", spec.palm_circumradius_mm, size);
  std::vector<double> lengths;
  for (const auto& l : spec.links) lengths.push_back(l.length_mm);
  lengths = t.numbers_or("link_lengths_mm", lengths, std::nullopt, size);
  if (lengths.empty()) t.fail("link_lengths_mm", "needs at least one link");
  const bool lengths_changed = lengths.size() != d.widths_mm.size() - 1;
  // The built-in widths fit the built-in number of links only.
  if (lengths_changed && !t.has("link_widths_mm")) {
    t.fail("link_widths_mm", "missing; link_lengths_mm gives " + std::to_string(lengths.size()) +
                                 " links, so the widths at their " + std::to_string(lengths.size() + 1) +
                                 " ends are needed (the built-in ones are for " +
                                 std::to_string(d.widths_mm.size() - 1) +
                                 (d.widths_mm.size() == 2 ? " link)" : " links)"));
  }
  std::vector<double> widths =
      t.numbers_or("link_widths_mm", d.widths_mm, lengths.size() + 1, Range::closed(0, ArticulatedModel::kMaxSizeMm));
  spec.links = links_from_config(t, lengths, widths);

  GripperGeometry g = make_radial_gripper(spec);
  g.joint_min_deg = t.number_or("joint_min_deg", d.joint_min_deg, Range::closed(-180, 180));
  g.joint_max_deg = t.number_or("joint_max_deg", d.joint_max_deg, Range::closed(-180, 180));
  if (!(g.joint_min_deg < g.joint_max_deg)) t.fail("joint_max_deg", "must be greater than joint_min_deg");
  g.collision.max_difference_deg =
      t.number_or("max_adjacent_difference_deg", d.max_adjacent_difference_deg, Range::positive());
  g.collision.max_sum_deg = t.number_or("max_adjacent_sum_deg", d.max_adjacent_sum_deg, Range::positive());
  // Joint values the tracker and synth start from: within the limits, the
  // defaults brought into limits set in the config.
  const Range limits = Range::closed(g.joint_min_deg, g.joint_max_deg);
  g.unfolded_deg =
      t.number_or("unfolded_deg", std::clamp(d.unfolded_deg, g.joint_min_deg, g.joint_max_deg), limits);
  g.folded_deg = t.number_or("folded_deg", std::clamp(d.folded_deg, g.joint_min_deg, g.joint_max_deg), limits);
  return g;
}

}  // namespace gtrack
